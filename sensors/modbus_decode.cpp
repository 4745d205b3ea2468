#include "sensors/modbus_decode.h"

#include <bit>
#include <stdexcept>
#include <string>

namespace doorbench::sensors {

int modbus_register_count(ModbusType type) {
  return type == ModbusType::kInt16 || type == ModbusType::kUint16 ? 1 : 2;
}

namespace {

// A register's 16 bits with its bytes in significance order (first byte on the wire most
// significant when the byte order is big).
std::uint16_t ordered_bytes(std::uint16_t reg, ModbusOrder byte_order) {
  if (byte_order == ModbusOrder::kBig) return reg;
  return static_cast<std::uint16_t>((reg >> 8) | (reg << 8));
}

}  // namespace

double decode_modbus_value(std::span<const std::uint16_t> registers, ModbusType type,
                           ModbusOrder byte_order, ModbusOrder word_order) {
  const int count = modbus_register_count(type);
  if (registers.size() != static_cast<std::size_t>(count)) {
    throw std::invalid_argument(std::string(modbus_type_name(type))
                                    .append(" needs ")
                                    .append(std::to_string(count))
                                    .append(" register(s), got ")
                                    .append(std::to_string(registers.size())));
  }
  if (count == 1) {
    const std::uint16_t bits = ordered_bytes(registers[0], byte_order);
    if (type == ModbusType::kInt16) return static_cast<double>(static_cast<std::int16_t>(bits));
    return static_cast<double>(bits);
  }
  const std::uint16_t first = ordered_bytes(registers[0], byte_order);
  const std::uint16_t second = ordered_bytes(registers[1], byte_order);
  const std::uint16_t high = word_order == ModbusOrder::kBig ? first : second;
  const std::uint16_t low = word_order == ModbusOrder::kBig ? second : first;
  const std::uint32_t bits = (static_cast<std::uint32_t>(high) << 16) | low;
  switch (type) {
    case ModbusType::kInt32:
      return static_cast<double>(static_cast<std::int32_t>(bits));
    case ModbusType::kUint32:
      return static_cast<double>(bits);
    default:
      return static_cast<double>(std::bit_cast<float>(bits));
  }
}

std::optional<ModbusType> modbus_type_from_name(std::string_view name) {
  if (name == "int16") return ModbusType::kInt16;
  if (name == "uint16") return ModbusType::kUint16;
  if (name == "int32") return ModbusType::kInt32;
  if (name == "uint32") return ModbusType::kUint32;
  if (name == "float32") return ModbusType::kFloat32;
  return std::nullopt;
}

std::string_view modbus_type_name(ModbusType type) {
  switch (type) {
    case ModbusType::kInt16:
      return "int16";
    case ModbusType::kUint16:
      return "uint16";
    case ModbusType::kInt32:
      return "int32";
    case ModbusType::kUint32:
      return "uint32";
    default:
      return "float32";
  }
}

std::optional<ModbusOrder> modbus_order_from_name(std::string_view name) {
  if (name == "big") return ModbusOrder::kBig;
  if (name == "little") return ModbusOrder::kLittle;
  return std::nullopt;
}

std::string_view modbus_order_name(ModbusOrder order) {
  return order == ModbusOrder::kBig ? "big" : "little";
}

}  // namespace doorbench::sensors
