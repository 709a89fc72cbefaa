#include "drivers/modbus_register_map.h"

#include <gtest/gtest.h>

namespace hairrig {
namespace {

TEST(ModbusRegisterMap, Int32RoundTripsInBothWordOrders) {
  for (WordOrder order : {WordOrder::kHighFirst, WordOrder::kLowFirst}) {
    for (int32_t v : {0, 1, -1, 65535, 65536, -123456789, 2147483647, -2147483647 - 1}) {
      uint16_t words[2];
      EncodeInt32(v, order, words);
      EXPECT_EQ(DecodeInt32(words, order), v);
    }
  }
  uint16_t words[2];
  EncodeInt32(0x12345678, WordOrder::kHighFirst, words);
  EXPECT_EQ(words[0], 0x1234);
  EXPECT_EQ(words[1], 0x5678);
  EncodeInt32(0x12345678, WordOrder::kLowFirst, words);
  EXPECT_EQ(words[0], 0x5678);
  EXPECT_EQ(words[1], 0x1234);
}

TEST(ModbusRegisterMap, DegreesAndCounts) {
  ModbusRegisterMap map;
  map.counts_per_degree = 1000;
  EXPECT_EQ(DegreesToCounts(-37.2506, map).value(), -37251);
  EXPECT_DOUBLE_EQ(CountsToDegrees(90000, map), 90.0);
  EXPECT_EQ(DegreesToCounts(3e6, map).status().code(), StatusCode::kOutOfRange);
  EXPECT_EQ(DegreesToCounts(std::nan(""), map).status().code(), StatusCode::kOutOfRange);
}

TEST(ModbusRegisterMap, AsciiSerialRoundTrips) {
  const std::vector<uint16_t> words = EncodeAscii("SIM-TT-0001", 8);
  ASSERT_EQ(words.size(), 8u);
  EXPECT_EQ(words[0], ('S' << 8) | 'I');
  EXPECT_EQ(words[5], ('1' << 8));
  EXPECT_EQ(DecodeAscii(words.data(), 8), "SIM-TT-0001");
  EXPECT_EQ(DecodeAscii(EncodeAscii("A-SERIAL-LONGER-THAN-16", 2).data(), 2), "A-SE");
}

Result<ModbusRegisterMap> Parse(const std::string& yaml) {
  auto node = ConfigNode::LoadString(yaml, "rig.yaml");
  EXPECT_TRUE(node.ok());
  return ParseModbusRegisterMap(*node);
}

TEST(ModbusRegisterMap, ParsesAProfileAndItsStatusBlock) {
  auto map = Parse(
      "registers: {status: 200, fault_code: 201, position: 210, target: 220}\n"
      "word_order: low_first\ncounts_per_degree: 3600\n"
      "commands: {move_absolute: 16}\nstatus_bits: {fault: 15}\nlimits: {max_speed_deg_s: 45}\n");
  ASSERT_TRUE(map.ok()) << map.status().ToString();
  EXPECT_EQ(map->word_order, WordOrder::kLowFirst);
  EXPECT_EQ(map->cmd_move_absolute, 16);
  EXPECT_EQ(map->bit_fault, 15);
  EXPECT_EQ(map->max_speed_deg_s, 45);
  EXPECT_EQ(map->StatusBlockStart(), 200);
  EXPECT_EQ(map->StatusBlockCount(), 22);
  EXPECT_EQ(map->RegisterSpan(), 222);
}

TEST(ModbusRegisterMap, ErrorsNameTheField) {
  auto overlap = Parse("registers: {position: 11}\n");
  EXPECT_FALSE(overlap.ok());
  EXPECT_NE(overlap.status().message().find("overlap"), std::string::npos)
      << overlap.status().ToString();
  auto bits = Parse("status_bits: {homed: 0}\n");
  EXPECT_NE(bits.status().message().find("share one bit"), std::string::npos)
      << bits.status().ToString();
  auto codes = Parse("commands: {home: 1}\n");
  EXPECT_NE(codes.status().message().find("share one code"), std::string::npos)
      << codes.status().ToString();
  auto order = Parse("word_order: middle\n");
  EXPECT_NE(order.status().message().find("word_order"), std::string::npos)
      << order.status().ToString();
  auto typo = Parse("registers: {postion: 40}\n");
  EXPECT_NE(typo.status().message().find("postion"), std::string::npos) << typo.status().ToString();
  auto far = Parse("registers: {status: 1, position: 300}\n");
  EXPECT_NE(far.status().message().find("125 registers"), std::string::npos)
      << far.status().ToString();
}

// No turntable turns ten times a second: such limits are a mistake.
TEST(ModbusRegisterMap, LimitsBeyondAnyTurntableAreRefused) {
  for (const std::string field : {"max_speed_deg_s", "max_accel_deg_s2"}) {
    auto map = Parse("limits: {" + field + ": 1e300}\n");
    ASSERT_FALSE(map.ok()) << field;
    EXPECT_NE(map.status().message().find("rig.yaml:1:"), std::string::npos)
        << map.status().ToString();
    EXPECT_NE(map.status().message().find("field 'limits." + field + "'"), std::string::npos)
        << map.status().ToString();
  }
}

// The controller's limits take the ranges of the capture plan's motion
// (core/config.h), so any plan speed or acceleration has a limit to match.
TEST(ModbusRegisterMap, LimitsTakeTheRangesOfThePlansMotion) {
  const std::vector<std::pair<std::string, NumberRange>> fields = {
      {"max_speed_deg_s", kTurntableSpeedRange}, {"max_accel_deg_s2", kTurntableAccelRange}};
  for (const auto& [field, range] : fields) {
    for (const double inside : {range.min, range.max}) {
      const auto map = Parse("limits: {" + field + ": " + std::to_string(inside) + "}\n");
      EXPECT_TRUE(map.ok()) << field << " " << inside << ": " << map.status().ToString();
    }
    const auto slower = Parse("limits: {" + field + ": " + std::to_string(range.min / 10) + "}\n");
    EXPECT_FALSE(slower.ok()) << field << " " << range.min / 10;
  }
}

}  // namespace
}  // namespace hairrig
