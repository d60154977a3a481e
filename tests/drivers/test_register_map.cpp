// Register maps and register codecs (pure), checked against libmodbus' own float helpers.
#include <gtest/gtest.h>
#include <modbus/modbus.h>

#include <fstream>
#include <numbers>
#include <sstream>

#include <hil/drivers/register_map.hpp>
#include <hil/test/drivers.hpp>

using namespace hil::drivers;

TEST(RegisterCodec, Float32WordOrdersMatchLibmodbus) {
  for (const float v : {0.0f, 1.5f, -123.456f, 3.4e38f, 1e-30f}) {
    // libmodbus' modbus_set_float writes the low word first (our little word order); its
    // *_abcd helpers swap bytes inside the words in 3.1.6, so big word order is checked by hand.
    std::uint16_t ours[2], theirs[2];
    set_float32(v, ours, WordOrder::little);
    modbus_set_float(v, theirs);
    EXPECT_EQ(ours[0], theirs[0]);
    EXPECT_EQ(ours[1], theirs[1]);
    EXPECT_EQ(get_float32(theirs, WordOrder::little), modbus_get_float(theirs));
    set_float32(v, ours, WordOrder::big);
    EXPECT_EQ(ours[0], theirs[1]);
    EXPECT_EQ(ours[1], theirs[0]);
    EXPECT_EQ(get_float32(ours, WordOrder::big), v);
  }
  std::uint16_t r[2] = {0x3FC0, 0x0000};  // 1.5f, high word first
  EXPECT_EQ(get_float32(r, WordOrder::big), 1.5f);
}

TEST(RegisterCodec, IntegersScaleAndOffset) {
  std::uint16_t r[2] = {0xFFFF, 0xFFFE};
  EXPECT_EQ(raw_value(RegisterType::int16, WordOrder::big, r), -1.0);
  EXPECT_EQ(raw_value(RegisterType::uint16, WordOrder::big, r), 65535.0);
  EXPECT_EQ(raw_value(RegisterType::int32, WordOrder::big, r), -2.0);
  EXPECT_EQ(raw_value(RegisterType::int32, WordOrder::little, r), static_cast<double>(static_cast<std::int32_t>(0xFFFEFFFF)));
  EXPECT_EQ(raw_value(RegisterType::uint32, WordOrder::big, r), 4294967294.0);
  RegisterEntry e;
  e.type = RegisterType::int32;
  e.word_order = WordOrder::little;
  e.scale = 1e-4;
  e.offset = -1.0;
  std::uint16_t w[2];
  encode_entry(e, 0.12346, w);
  EXPECT_NEAR(decode_entry(e, w), 0.12346, 0.5e-4 + 1e-12);
  e.type = RegisterType::int16;
  encode_entry(e, 1e9, w);  // saturates
  EXPECT_EQ(static_cast<std::int16_t>(w[0]), 32767);
}

TEST(RegisterCodec, UrJointsUseTheRevolutionCounter) {
  const RegisterMap ur = ur_register_map();
  const RegisterEntry& j1 = ur.entries[0];
  ASSERT_EQ(j1.address, 270U);
  ASSERT_EQ(j1.turns_address, 320);
  std::uint16_t raw = 0, turns = 0;
  encode_entry(j1, -0.5, &raw, &turns);
  EXPECT_EQ(raw, 5783);     // within the turn: 2π - 0.5 rad in mrad
  EXPECT_EQ(turns, 65535);  // -1: a negative angle
  EXPECT_NEAR(decode_entry(j1, &raw, static_cast<std::int16_t>(turns)), -0.5, 1e-3);
  encode_entry(j1, 1.25, &raw, &turns);
  EXPECT_EQ(raw, 1250);
  EXPECT_EQ(turns, 0);
  for (double q = -6.2; q < 6.2; q += 0.0137) {
    encode_entry(j1, q, &raw, &turns);
    ASSERT_NEAR(decode_entry(j1, &raw, static_cast<std::int16_t>(turns)), q, 0.5e-3 + 1e-12) << q;
  }
  // Tool pose: 0.1 mm and mrad, two's complement.
  const RegisterEntry& px = ur.entries[6];
  EXPECT_EQ(px.address, 400U);
  encode_entry(px, -0.45, &raw);
  EXPECT_EQ(static_cast<std::int16_t>(raw), -4500);
}

TEST(RegisterMapTest, ReadPlansGroupRegisters) {
  const auto ur = plan_reads(ur_register_map());
  ASSERT_EQ(ur.size(), 3U);
  EXPECT_EQ(ur[0].address, 270U);
  EXPECT_EQ(ur[0].count, 6U);
  EXPECT_EQ(ur[1].address, 320U);
  EXPECT_EQ(ur[2].address, 400U);
  const auto f = plan_reads(float32_register_map());
  ASSERT_EQ(f.size(), 1U);
  EXPECT_EQ(f[0].count, 24U);
  RegisterMap m;
  m.entries = {{"j1", 0, RegisterTable::holding, RegisterType::int16, WordOrder::big, 1, 0, -1},
               {"j2", 200, RegisterTable::holding, RegisterType::float32, WordOrder::big, 1, 0, -1},
               {"j3", 5, RegisterTable::input, RegisterType::int16, WordOrder::big, 1, 0, -1}};
  const auto p = plan_reads(m, 16, 125);
  ASSERT_EQ(p.size(), 3U);
  EXPECT_EQ(p[1].address, 200U);
  EXPECT_EQ(p[1].count, 2U);
  EXPECT_EQ(p[2].table, RegisterTable::input);
  EXPECT_EQ(plan_reads(m, 1000, 125).size(), 3U);  // 0..201 exceeds 125 registers
}

TEST(RegisterMapTest, ReadPlansNeverSplitAValue) {
  // A float32 at 124-125 straddles the 125-register limit of a read starting at 0: planned whole,
  // in one read, it cannot be torn between two polls (found by fuzz_register_map).
  RegisterMap m;
  m.entries = {{"j1", 0, RegisterTable::holding, RegisterType::int16, WordOrder::big, 1, 0, -1},
               {"j2", 124, RegisterTable::holding, RegisterType::float32, WordOrder::big, 1, 0, -1}};
  for (unsigned max_count : {125U, 10U, 2U}) {
    const auto plan = plan_reads(m, 1000, max_count);
    for (const auto& e : m.entries) {
      bool whole = false;
      for (const auto& b : plan) whole = whole || (b.table == e.table && b.address <= e.address && e.address + 2 <= b.address + b.count);
      EXPECT_TRUE(whole || e.type == RegisterType::int16) << e.quantity << " split with max_count " << max_count;
    }
    for (const auto& b : plan) EXPECT_LE(b.count, max_count);
  }
}

TEST(RegisterMapTest, ValidationNamesTheEntry) {
  using hil::test::config_error;
  RegisterMap m = float32_register_map();
  m.validate();
  EXPECT_EQ(m.joint_count(), 6U);
  EXPECT_TRUE(m.has_pose());
  m.entries[1].address = 1;  // j2 overlaps j1
  EXPECT_TRUE(config_error([&] { m.validate(); }, "registers[1].address", "register 1 overlaps registers[0] ('j1')"));
  m = float32_register_map();
  m.entries[3].quantity = "q4";
  EXPECT_TRUE(config_error([&] { m.validate(); }, "registers[3].quantity", "'q4' is not a quantity"));
  m = float32_register_map();
  m.entries[1].quantity = "j9";
  EXPECT_TRUE(config_error([&] { m.validate(); }, "registers", "j2 is missing"));
  m = float32_register_map();
  m.entries.pop_back();
  EXPECT_TRUE(config_error([&] { m.validate(); }, "registers", "needs all of px py pz rx ry rz"));
  m = float32_register_map();
  m.entries[0].scale = 0;
  EXPECT_TRUE(config_error([&] { m.validate(); }, "registers[0].scale", "non-zero"));
  EXPECT_TRUE(config_error([] { parse_register_type("float64", "registers[2].type"); }, "registers[2].type", "not a register type"));
  EXPECT_TRUE(config_error([] { builtin_register_map("kuka"); }, "register_map", "not a built-in map"));
}

// The driver is read-only by construction: its source calls no libmodbus write function.
TEST(ReadOnly, DriverSourceHasNoWriteCall) {
  std::ifstream in(std::string(HIL_SOURCE_DIR) + "/drivers/src/robot_controller.cpp");
  ASSERT_TRUE(in.good());
  std::stringstream ss;
  ss << in.rdbuf();
  const std::string src = ss.str();
  for (const char* w : {"modbus_write", "modbus_mask_write", "modbus_write_and_read", "modbus_send_raw_request"})
    EXPECT_EQ(src.find(std::string(w) + "_"), std::string::npos) << w;
  EXPECT_EQ(src.find("modbus_write_register"), std::string::npos);
  EXPECT_EQ(src.find("modbus_write_bit"), std::string::npos);
  EXPECT_EQ(src.find("modbus_send_raw_request"), std::string::npos);
}
