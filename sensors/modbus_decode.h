#pragma once
// Decoding Modbus registers (16-bit words as libmodbus hands them over, host order) into
// numbers, by hand: libmodbus' modbus_get_float_* helpers are not used because Debian's
// version disagrees with its own documentation about which order each one reads.
//
// Notation (docs/modbus.md): a value's bytes from most to least significant are A B C D
// (int16/uint16: A B). byte_order says how the two bytes sit within each register on the
// wire: big = the register holds A B (the Modbus standard), little = B A. word_order says
// which register comes first for 32-bit types: big = the first register holds the high
// half (A B), little = the low half (C D) first. So big/big is ABCD, big/little CDAB,
// little/big BADC, little/little DCBA.
#include <cstdint>
#include <optional>
#include <span>
#include <string_view>

namespace doorbench::sensors {

enum class ModbusType { kInt16, kUint16, kInt32, kUint32, kFloat32 };
enum class ModbusOrder { kBig, kLittle };

// Registers one value occupies: 1 for 16-bit types, 2 for 32-bit ones.
int modbus_register_count(ModbusType type);

// The value of `type` held in `registers` (exactly modbus_register_count(type) of them);
// throws std::invalid_argument on a wrong count. Allocates nothing otherwise.
double decode_modbus_value(std::span<const std::uint16_t> registers, ModbusType type,
                           ModbusOrder byte_order, ModbusOrder word_order);

// Names as in rig files ("int16", "float32", "big", "little"); nullopt when unknown.
std::optional<ModbusType> modbus_type_from_name(std::string_view name);
std::string_view modbus_type_name(ModbusType type);
std::optional<ModbusOrder> modbus_order_from_name(std::string_view name);
std::string_view modbus_order_name(ModbusOrder order);

}  // namespace doorbench::sensors
