#include <hil/drivers/register_map.hpp>

#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>
#include <map>
#include <numbers>
#include <set>

#include <hil/drivers/error.hpp>

namespace hil::drivers {

RegisterType parse_register_type(const std::string& s, const std::string& field) {
  if (s == "int16") return RegisterType::int16;
  if (s == "uint16") return RegisterType::uint16;
  if (s == "int32") return RegisterType::int32;
  if (s == "uint32") return RegisterType::uint32;
  if (s == "float32") return RegisterType::float32;
  throw ConfigError(field, "'" + s + "' is not a register type (int16 uint16 int32 uint32 float32)");
}

WordOrder parse_word_order(const std::string& s, const std::string& field) {
  if (s == "big") return WordOrder::big;
  if (s == "little") return WordOrder::little;
  throw ConfigError(field, "'" + s + "' is not a word order (big = high word first, little)");
}

RegisterTable parse_register_table(const std::string& s, const std::string& field) {
  if (s == "holding") return RegisterTable::holding;
  if (s == "input") return RegisterTable::input;
  throw ConfigError(field, "'" + s + "' is not a register table (holding, input)");
}

const char* to_string(RegisterType t) noexcept {
  switch (t) {
    case RegisterType::int16: return "int16";
    case RegisterType::uint16: return "uint16";
    case RegisterType::int32: return "int32";
    case RegisterType::uint32: return "uint32";
    case RegisterType::float32: return "float32";
  }
  return "?";
}

unsigned register_count(RegisterType t) noexcept { return t == RegisterType::int16 || t == RegisterType::uint16 ? 1U : 2U; }

Quantity parse_quantity(const std::string& s, const std::string& field) {
  static const std::map<std::string, Quantity::Kind> pose{{"px", Quantity::Kind::px}, {"py", Quantity::Kind::py},
                                                          {"pz", Quantity::Kind::pz}, {"rx", Quantity::Kind::rx},
                                                          {"ry", Quantity::Kind::ry}, {"rz", Quantity::Kind::rz}};
  if (auto it = pose.find(s); it != pose.end()) return Quantity{it->second, 0};
  if (s.size() >= 2 && s.size() <= 3 && s[0] == 'j' && s[1] >= '1' && s[1] <= '9' &&
      std::all_of(s.begin() + 1, s.end(), [](char c) { return c >= '0' && c <= '9'; })) {
    const unsigned n = static_cast<unsigned>(std::stoul(s.substr(1)));
    if (n >= 1 && n <= kMaxJoints) return Quantity{Quantity::Kind::joint, n - 1};
  }
  throw ConfigError(field, "'" + s + "' is not a quantity (j1..j16, px py pz, rx ry rz)");
}

void RegisterMap::validate() const {
  if (entries.empty()) throw ConfigError("registers", "the register map '" + name + "' is empty");
  std::set<std::string> seen;
  std::map<std::pair<RegisterTable, unsigned>, std::size_t> used;
  for (std::size_t i = 0; i < entries.size(); ++i) {
    const auto& e = entries[i];
    const std::string f = "registers[" + std::to_string(i) + "].";
    parse_quantity(e.quantity, f + "quantity");
    if (!seen.insert(e.quantity).second) throw ConfigError(f + "quantity", "'" + e.quantity + "' is mapped twice");
    if (e.address + register_count(e.type) > 65536) throw ConfigError(f + "address", "beyond register 65535");
    if (!std::isfinite(e.scale) || e.scale == 0.0) throw ConfigError(f + "scale", "must be finite and non-zero");
    if (!std::isfinite(e.offset)) throw ConfigError(f + "offset", "must be finite");
    if (e.turns_address > 65535) throw ConfigError(f + "turns_address", "beyond register 65535");
    for (unsigned k = 0; k < register_count(e.type); ++k) {
      auto [it, fresh] = used.insert({{e.table, e.address + k}, i});
      if (!fresh)
        throw ConfigError(f + "address", "register " + std::to_string(e.address + k) + " overlaps registers[" + std::to_string(it->second) +
                                             "] ('" + entries[it->second].quantity + "')");
    }
  }
  const unsigned n = joint_count();
  for (unsigned j = 0; j < n; ++j)
    if (!seen.count("j" + std::to_string(j + 1)))
      throw ConfigError("registers",
                        "joints must be j1..j" + std::to_string(n) + " without gaps: j" + std::to_string(j + 1) + " is missing");
  int pose_parts = 0;
  for (const char* q : {"px", "py", "pz", "rx", "ry", "rz"}) pose_parts += static_cast<int>(seen.count(q));
  if (pose_parts != 0 && pose_parts != 6) throw ConfigError("registers", "the tool pose needs all of px py pz rx ry rz");
  if (n == 0 && pose_parts == 0) throw ConfigError("registers", "maps neither joints nor the tool pose");
}

unsigned RegisterMap::joint_count() const {
  unsigned n = 0;
  for (const auto& e : entries) {
    try {
      const Quantity q = parse_quantity(e.quantity, "");
      if (q.kind == Quantity::Kind::joint) n = std::max(n, q.joint + 1);
    } catch (const ConfigError&) {
    }
  }
  return n;
}

bool RegisterMap::has_pose() const {
  int parts = 0;
  for (const auto& e : entries)
    for (const char* q : {"px", "py", "pz", "rx", "ry", "rz"}) parts += e.quantity == q ? 1 : 0;
  return parts == 6;
}

RegisterMap ur_register_map() {
  RegisterMap m;
  m.name = "ur";
  for (unsigned j = 0; j < 6; ++j) {
    RegisterEntry e;
    e.quantity = "j" + std::to_string(j + 1);
    e.address = 270 + j;
    e.type = RegisterType::uint16;
    e.scale = 1e-3;
    e.turns_address = static_cast<int>(320 + j);
    m.entries.push_back(e);
  }
  const char* pose[] = {"px", "py", "pz", "rx", "ry", "rz"};
  for (unsigned k = 0; k < 6; ++k) {
    RegisterEntry e;
    e.quantity = pose[k];
    e.address = 400 + k;
    e.type = RegisterType::int16;
    e.scale = k < 3 ? 1e-4 : 1e-3;
    m.entries.push_back(e);
  }
  return m;
}

RegisterMap float32_register_map() {
  RegisterMap m;
  m.name = "float32";
  const char* names[] = {"j1", "j2", "j3", "j4", "j5", "j6", "px", "py", "pz", "rx", "ry", "rz"};
  for (unsigned k = 0; k < 12; ++k) {
    RegisterEntry e;
    e.quantity = names[k];
    e.address = 2 * k;
    e.type = RegisterType::float32;
    m.entries.push_back(e);
  }
  return m;
}

RegisterMap builtin_register_map(const std::string& name) {
  if (name == "ur") return ur_register_map();
  if (name == "float32") return float32_register_map();
  throw ConfigError("register_map", "'" + name + "' is not a built-in map (ur, float32; or custom with registers)");
}

std::uint32_t get_u32(const std::uint16_t* r, WordOrder o) noexcept {
  return o == WordOrder::big ? (static_cast<std::uint32_t>(r[0]) << 16) | r[1] : (static_cast<std::uint32_t>(r[1]) << 16) | r[0];
}

void set_u32(std::uint32_t v, std::uint16_t* r, WordOrder o) noexcept {
  const auto hi = static_cast<std::uint16_t>(v >> 16), lo = static_cast<std::uint16_t>(v);
  if (o == WordOrder::big) {
    r[0] = hi;
    r[1] = lo;
  } else {
    r[0] = lo;
    r[1] = hi;
  }
}

float get_float32(const std::uint16_t* r, WordOrder o) noexcept { return std::bit_cast<float>(get_u32(r, o)); }
void set_float32(float v, std::uint16_t* r, WordOrder o) noexcept { set_u32(std::bit_cast<std::uint32_t>(v), r, o); }

double raw_value(RegisterType t, WordOrder o, const std::uint16_t* r) noexcept {
  switch (t) {
    case RegisterType::int16: return static_cast<std::int16_t>(r[0]);
    case RegisterType::uint16: return r[0];
    case RegisterType::int32: return static_cast<std::int32_t>(get_u32(r, o));
    case RegisterType::uint32: return get_u32(r, o);
    case RegisterType::float32: return get_float32(r, o);
  }
  return 0.0;
}

double decode_entry(const RegisterEntry& e, const std::uint16_t* regs, std::int16_t turns) noexcept {
  double v = raw_value(e.type, e.word_order, regs) * e.scale + e.offset;
  if (e.turns_address >= 0) v += 2.0 * std::numbers::pi * turns;
  return v;
}

namespace {
template <typename T>
T saturate_round(double x) noexcept {
  const double lo = static_cast<double>(std::numeric_limits<T>::min());
  const double hi = static_cast<double>(std::numeric_limits<T>::max());
  if (!(x == x)) return T{0};
  const double r = std::nearbyint(x);
  return static_cast<T>(r < lo ? lo : r > hi ? hi : r);
}
}  // namespace

void encode_entry(const RegisterEntry& e, double value, std::uint16_t* regs, std::uint16_t* turns) noexcept {
  if (e.turns_address >= 0) {
    const double two_pi = 2.0 * std::numbers::pi;
    double rev = std::floor((value - e.offset) / two_pi);
    double rem = value - rev * two_pi;
    // Rounding may carry a value just below one turn into the next turn.
    if (std::nearbyint((rem - e.offset) / e.scale) * e.scale + e.offset >= two_pi) {
      rev += 1.0;
      rem -= two_pi;
    }
    if (turns != nullptr) *turns = static_cast<std::uint16_t>(saturate_round<std::int16_t>(rev));
    value = rem;
  }
  const double raw = (value - e.offset) / e.scale;
  switch (e.type) {
    case RegisterType::int16: regs[0] = static_cast<std::uint16_t>(saturate_round<std::int16_t>(raw)); break;
    case RegisterType::uint16: regs[0] = saturate_round<std::uint16_t>(raw); break;
    case RegisterType::int32: set_u32(static_cast<std::uint32_t>(saturate_round<std::int32_t>(raw)), regs, e.word_order); break;
    case RegisterType::uint32: set_u32(saturate_round<std::uint32_t>(raw), regs, e.word_order); break;
    case RegisterType::float32: set_float32(static_cast<float>(raw), regs, e.word_order); break;
  }
}

std::vector<ReadBlock> plan_reads(const RegisterMap& map, unsigned max_gap, unsigned max_count) {
  std::vector<ReadBlock> out;
  for (const RegisterTable table : {RegisterTable::holding, RegisterTable::input}) {
    // Each value is planned whole (first -> last register): found by fuzzing, a 32-bit value at
    // a block's max_count boundary was split over two reads, so its words could come from two
    // different instants (a torn float).
    std::map<unsigned, unsigned> units;
    for (const auto& e : map.entries) {
      if (e.table != table) continue;
      const unsigned last = e.address + register_count(e.type) - 1;
      auto [it, fresh] = units.try_emplace(e.address, last);
      if (!fresh) it->second = std::max(it->second, last);
      if (e.turns_address >= 0) units.try_emplace(static_cast<unsigned>(e.turns_address), static_cast<unsigned>(e.turns_address));
    }
    ReadBlock cur;
    bool open = false;
    for (const auto& [first, last] : units) {
      const unsigned end = cur.address + cur.count;
      if (open && (first < end || (first - end <= max_gap && last + 1 - cur.address <= max_count))) {
        cur.count = std::max(cur.count, last + 1 - cur.address);
        continue;
      }
      if (open) out.push_back(cur);
      cur = ReadBlock{table, first, last + 1 - first};
      open = true;
    }
    if (open) out.push_back(cur);
  }
  return out;
}

}  // namespace hil::drivers
