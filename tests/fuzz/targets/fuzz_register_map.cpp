// Modbus register maps (drivers/src/register_map.cpp). The first byte picks the map: UR's,
// hil's float32, or a custom one built from the next bytes (which validate() must refuse with
// ConfigError when bad). Then the reads are planned, every register a valid map needs must lie
// in a planned block of at most max_count registers, and each entry is decoded from a block
// filled with the remaining input.
#include <map>
#include <vector>
#include "fuzz_common.hpp"
#include <hil/drivers/error.hpp>
#include <hil/drivers/register_map.hpp>

using namespace hil::drivers;

namespace {
const char* const kQuantities[] = {"j1", "j2", "j3", "j4", "j5", "j6", "j7", "j16", "j17", "px",
                                   "py", "pz", "rx", "ry", "rz", "x",  "",   "j0",  "J1"};

bool covered(const std::vector<ReadBlock>& blocks, RegisterTable t, unsigned addr, const ReadBlock** hit) {
  for (const auto& b : blocks)
    if (b.table == t && addr >= b.address && addr < b.address + b.count) return *hit = &b, true;
  return false;
}
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  hil::fuzz::Bytes in(data, size);
  RegisterMap map;
  const std::uint8_t pick = in.u8();
  if (pick % 4 == 0) {
    map = ur_register_map();
  } else if (pick % 4 == 1) {
    map = float32_register_map();
  } else {
    const unsigned n = in.u8() % 24;
    for (unsigned i = 0; i < n; ++i) {
      RegisterEntry e;
      e.quantity = kQuantities[in.u8() % (sizeof kQuantities / sizeof *kQuantities)];
      const std::uint8_t flags = in.u8();
      e.address = (flags & 1) ? in.u16() : in.u8();
      e.table = (flags & 2) ? RegisterTable::input : RegisterTable::holding;
      e.type = static_cast<RegisterType>((flags >> 2) % 5);
      e.word_order = (flags & 32) ? WordOrder::little : WordOrder::big;
      e.scale = (flags & 64) ? 0.0 : 1.0 / (1 + in.u8());
      e.turns_address = (flags & 128) ? static_cast<int>(in.u16()) - 1 : -1;
      map.entries.push_back(e);
    }
  }
  const unsigned max_gap = in.u8() % 20;
  const unsigned max_count = 2 + in.u8() % 124;
  try {
    map.validate();
  } catch (const ConfigError&) {
    return 0;
  } catch (const std::exception& e) {
    hil::fuzz::unexpected("fuzz_register_map", &e);
  }
  try {
    (void)map.joint_count();
    (void)map.has_pose();
    const auto blocks = plan_reads(map, max_gap, max_count);
    std::map<const ReadBlock*, std::vector<std::uint16_t>> regs;
    for (const auto& b : blocks) {
      if (b.count == 0 || b.count > max_count) hil::fuzz::violated("fuzz_register_map", "block size out of 1..max_count");
      auto& r = regs[&b];
      for (unsigned i = 0; i < b.count; ++i) r.push_back(in.u16());
    }
    for (const auto& e : map.entries) {
      const ReadBlock* b = nullptr;
      const ReadBlock* b2 = nullptr;
      if (!covered(blocks, e.table, e.address, &b) || !covered(blocks, e.table, e.address + register_count(e.type) - 1, &b2) || b != b2)
        hil::fuzz::violated("fuzz_register_map", "an entry's registers are not read in one block");
      std::int16_t turns = 0;
      if (e.turns_address >= 0) {
        const ReadBlock* tb = nullptr;
        if (!covered(blocks, e.table, static_cast<unsigned>(e.turns_address), &tb))
          hil::fuzz::violated("fuzz_register_map", "a turns register is not read");
        turns = static_cast<std::int16_t>(regs[tb][static_cast<unsigned>(e.turns_address) - tb->address]);
      }
      const double v = decode_entry(e, &regs[b][e.address - b->address], turns);
      std::uint16_t back[2] = {0, 0};
      std::uint16_t back_turns = 0;
      encode_entry(e, v, back, &back_turns);
    }
  } catch (const std::exception& e) {
    hil::fuzz::unexpected("fuzz_register_map", &e);
  }
  return 0;
}
