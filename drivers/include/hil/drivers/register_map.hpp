#pragma once
/// \file Robot-controller register maps and the pure register codecs (after libmodbus'
/// modbus-data.c): 16/32-bit integers and float32 over two registers in either word order,
/// scale and offset, UR revolution counters, and grouping of a map into block reads.
#include <cstdint>
#include <string>
#include <vector>

namespace hil::drivers {

enum class RegisterType : std::uint8_t { int16, uint16, int32, uint32, float32 };
enum class WordOrder : std::uint8_t { big, little };  ///< 32-bit values: big = high word at the lower address
enum class RegisterTable : std::uint8_t { holding, input };

RegisterType parse_register_type(const std::string& s, const std::string& field);
WordOrder parse_word_order(const std::string& s, const std::string& field);
RegisterTable parse_register_table(const std::string& s, const std::string& field);
const char* to_string(RegisterType t) noexcept;
/// Registers a value of this type occupies (1 or 2).
unsigned register_count(RegisterType t) noexcept;

/// What a register holds: a joint angle j1..j16 (rad or m), the tool position px py pz (m) or the
/// tool orientation as a rotation vector rx ry rz (rad), all in the robot base frame.
struct Quantity {
  enum class Kind : std::uint8_t { joint, px, py, pz, rx, ry, rz } kind = Kind::joint;
  unsigned joint = 0;  ///< 0-based joint index
};
/// \throws ConfigError(field) for anything but j1..j16, px, py, pz, rx, ry, rz.
Quantity parse_quantity(const std::string& s, const std::string& field);

inline constexpr unsigned kMaxJoints = 16;

struct RegisterEntry {
  std::string quantity;  ///< j1..j16, px py pz (m), rx ry rz (rotation vector, rad)
  unsigned address = 0;
  RegisterTable table = RegisterTable::holding;
  RegisterType type = RegisterType::int16;
  WordOrder word_order = WordOrder::big;
  double scale = 1.0;  ///< value = raw * scale + offset (+ 2π · turns)
  double offset = 0.0;
  int turns_address = -1;  ///< UR: register with the joint's revolution count (int16), -1 = none
};

struct RegisterMap {
  std::string name = "custom";
  std::vector<RegisterEntry> entries;
  /// \throws ConfigError naming `registers[i].<field>` (unknown quantity, duplicates, overlaps, scale 0, ...).
  void validate() const;
  unsigned joint_count() const;  ///< highest joint index + 1 (joints must be j1..jN without gaps)
  bool has_pose() const;         ///< all of px py pz rx ry rz present
};

/// Universal Robots' Modbus server (holding registers): joint angles at 270-275 in mrad (uint16,
/// within one turn) with the revolution counters of 320-325 (int16, 0 or -1), tool pose at 400-405:
/// x y z in 0.1 mm and rx ry rz in mrad, int16 two's complement.
RegisterMap ur_register_map();
/// hil's float32 map (holding registers, big word order): j1..j6 (rad) at 0, 2, .., 10; px py pz (m)
/// at 12, 14, 16; rx ry rz (rad) at 18, 20, 22.
RegisterMap float32_register_map();
/// "ur" or "float32". \throws ConfigError.
RegisterMap builtin_register_map(const std::string& name);

// ---- pure codecs -------------------------------------------------------------------------------
std::uint32_t get_u32(const std::uint16_t* regs, WordOrder order) noexcept;
void set_u32(std::uint32_t v, std::uint16_t* regs, WordOrder order) noexcept;
float get_float32(const std::uint16_t* regs, WordOrder order) noexcept;
void set_float32(float v, std::uint16_t* regs, WordOrder order) noexcept;

/// The raw register value as a number (no scale). \pre regs holds register_count(type) registers.
double raw_value(RegisterType type, WordOrder order, const std::uint16_t* regs) noexcept;
/// Physical value of an entry: raw * scale + offset + 2π · turns.
double decode_entry(const RegisterEntry& e, const std::uint16_t* regs, std::int16_t turns = 0) noexcept;
/// Inverse (for servers and fakes): rounds and saturates integers; writes turns if the entry has them.
void encode_entry(const RegisterEntry& e, double value, std::uint16_t* regs, std::uint16_t* turns = nullptr) noexcept;

/// One read request.
struct ReadBlock {
  RegisterTable table = RegisterTable::holding;
  unsigned address = 0;
  unsigned count = 0;
};
/// Groups every register a map needs into as few reads as possible (gaps up to `max_gap` are read
/// through; at most `max_count` registers per read, Modbus allows 125).
std::vector<ReadBlock> plan_reads(const RegisterMap& map, unsigned max_gap = 16, unsigned max_count = 125);

}  // namespace hil::drivers
