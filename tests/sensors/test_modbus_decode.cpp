// Register decoding against byte patterns worked out by hand (docs/modbus.md notation).
#include <array>
#include <catch2/catch.hpp>
#include <cstdint>
#include <stdexcept>

#include "sensors/modbus_decode.h"

using doorbench::sensors::decode_modbus_value;
using doorbench::sensors::ModbusOrder;
using doorbench::sensors::ModbusType;

namespace {
constexpr ModbusOrder kBig = ModbusOrder::kBig;
constexpr ModbusOrder kLittle = ModbusOrder::kLittle;

double decode(std::array<std::uint16_t, 2> regs, ModbusType type, ModbusOrder bytes,
              ModbusOrder words) {
  return decode_modbus_value(regs, type, bytes, words);
}
}  // namespace

TEST_CASE("modbus decode: float32 1.5 (0x3FC00000) in all four orders", "[modbus]") {
  // A=0x3F B=0xC0 C=0x00 D=0x00
  CHECK(decode({0x3FC0, 0x0000}, ModbusType::kFloat32, kBig, kBig) == 1.5);        // ABCD
  CHECK(decode({0x0000, 0x3FC0}, ModbusType::kFloat32, kBig, kLittle) == 1.5);     // CDAB
  CHECK(decode({0xC03F, 0x0000}, ModbusType::kFloat32, kLittle, kBig) == 1.5);     // BADC
  CHECK(decode({0x0000, 0xC03F}, ModbusType::kFloat32, kLittle, kLittle) == 1.5);  // DCBA
  // The wrong order gives another number, so the test can tell orders apart.
  CHECK(decode({0x3FC0, 0x0000}, ModbusType::kFloat32, kBig, kLittle) != 1.5);
}

TEST_CASE("modbus decode: float32 with all four bytes distinct", "[modbus]") {
  // -123.456f = 0xC2F6E979: A=C2 B=F6 C=E9 D=79
  const double expected = static_cast<double>(-123.456f);
  CHECK(decode({0xC2F6, 0xE979}, ModbusType::kFloat32, kBig, kBig) == expected);
  CHECK(decode({0xE979, 0xC2F6}, ModbusType::kFloat32, kBig, kLittle) == expected);
  CHECK(decode({0xF6C2, 0x79E9}, ModbusType::kFloat32, kLittle, kBig) == expected);
  CHECK(decode({0x79E9, 0xF6C2}, ModbusType::kFloat32, kLittle, kLittle) == expected);
}

TEST_CASE("modbus decode: negative int32 -123456789 (0xF8A432EB) in all four orders", "[modbus]") {
  CHECK(decode({0xF8A4, 0x32EB}, ModbusType::kInt32, kBig, kBig) == -123456789.0);
  CHECK(decode({0x32EB, 0xF8A4}, ModbusType::kInt32, kBig, kLittle) == -123456789.0);
  CHECK(decode({0xA4F8, 0xEB32}, ModbusType::kInt32, kLittle, kBig) == -123456789.0);
  CHECK(decode({0xEB32, 0xA4F8}, ModbusType::kInt32, kLittle, kLittle) == -123456789.0);
  // The same bits unsigned.
  CHECK(decode({0xF8A4, 0x32EB}, ModbusType::kUint32, kBig, kBig) == 4171510507.0);
}

TEST_CASE("modbus decode: 16-bit types and byte order", "[modbus]") {
  const std::array<std::uint16_t, 1> minus_two{0xFFFE};
  CHECK(decode_modbus_value(minus_two, ModbusType::kInt16, kBig, kBig) == -2.0);
  CHECK(decode_modbus_value(minus_two, ModbusType::kUint16, kBig, kBig) == 65534.0);
  // 0x1234 sent little: the register reads 0x3412; word order does not matter.
  const std::array<std::uint16_t, 1> swapped{0x3412};
  CHECK(decode_modbus_value(swapped, ModbusType::kUint16, kLittle, kLittle) == 0x1234);
  CHECK(decode_modbus_value(swapped, ModbusType::kUint16, kLittle, kBig) == 0x1234);
  const std::array<std::uint16_t, 1> most_negative{0x0080};  // 0x8000 little
  CHECK(decode_modbus_value(most_negative, ModbusType::kInt16, kLittle, kBig) == -32768.0);
}

TEST_CASE("modbus decode: a wrong register count is an error naming the type", "[modbus]") {
  const std::array<std::uint16_t, 1> one{0};
  CHECK_THROWS_WITH(decode_modbus_value(one, ModbusType::kFloat32, kBig, kBig),
                    "float32 needs 2 register(s), got 1");
}

TEST_CASE("modbus decode: names", "[modbus]") {
  using namespace doorbench::sensors;
  for (const char* name : {"int16", "uint16", "int32", "uint32", "float32"}) {
    REQUIRE(modbus_type_from_name(name));
    CHECK(modbus_type_name(*modbus_type_from_name(name)) == name);
  }
  CHECK_FALSE(modbus_type_from_name("float64"));
  CHECK(modbus_order_from_name("little") == ModbusOrder::kLittle);
  CHECK_FALSE(modbus_order_from_name("middle"));
}
