// Decoding speed of the device layer (issue target: ≥ 5 M frames/s decoded).
//   bench_drivers --benchmark_filter=Decode
#include <benchmark/benchmark.h>

#include <random>
#include <vector>

#include <hil/drivers/ati_protocol.hpp>
#include <hil/drivers/candump.hpp>
#include <hil/drivers/can_frame.hpp>
#include <hil/drivers/force_plate.hpp>
#include <hil/drivers/netft_rdt.hpp>
#include <hil/drivers/register_map.hpp>

using namespace hil::drivers;

namespace {

std::vector<std::array<std::uint8_t, kCanFdMtu>> kernel_frames(std::size_t n) {
  std::mt19937 rng(1);
  std::vector<std::array<std::uint8_t, kCanFdMtu>> out(n);
  for (auto& b : out) {
    CanFrame f;
    f.id = rng() & 0x7FF;
    f.len = 8;
    for (auto& d : f.data) d = static_cast<std::uint8_t>(rng());
    encode_kernel_frame(f, std::span<std::uint8_t, kCanFdMtu>(b));
  }
  return out;
}

}  // namespace

// Kernel bytes (what recvmsg gives) → CanFrame.
static void BM_DecodeKernelFrame(benchmark::State& state) {
  const auto frames = kernel_frames(1024);
  CanFrame f;
  std::size_t i = 0;
  for (auto _ : state) {
    const auto st = decode_kernel_frame(std::span<const std::uint8_t>(frames[i & 1023].data(), kCanMtu), f);
    benchmark::DoNotOptimize(st);
    benchmark::DoNotOptimize(f);
    ++i;
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()));
}
BENCHMARK(BM_DecodeKernelFrame);

// Kernel bytes → CanFrame → ATI gauges → wrench (one frame of the pair per iteration).
static void BM_DecodeAtiGaugeFrames(benchmark::State& state) {
  std::array<std::array<std::uint8_t, kCanFdMtu>, 2> raw{};
  const auto fr = ati::encode_gauges(0, 0, {100, -200, 300, -400, 500, -600});
  encode_kernel_frame(fr[0], std::span<std::uint8_t, kCanFdMtu>(raw[0]));
  encode_kernel_frame(fr[1], std::span<std::uint8_t, kCanFdMtu>(raw[1]));
  Matrix6d G = Matrix6d::Identity() * 1e-3;
  CanFrame f;
  ati::Gauges g{};
  std::uint16_t status = 0;
  Vector6d w;
  std::size_t i = 0;
  for (auto _ : state) {
    decode_kernel_frame(std::span<const std::uint8_t>(raw[i & 1].data(), kCanMtu), f);
    if ((i & 1) == 0) {
      ati::decode_gauges_first(f, status, g);
    } else {
      ati::decode_gauges_second(f, g);
      Eigen::Matrix<double, 6, 1> gv;
      for (int k = 0; k < 6; ++k) gv[k] = g[static_cast<std::size_t>(k)];
      w.noalias() = G * gv;
      benchmark::DoNotOptimize(w);
    }
    ++i;
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()));
}
BENCHMARK(BM_DecodeAtiGaugeFrames);

// A declarative frame with three 16-bit signals.
// Net F/T RDT records (36 bytes each, as the datagram holds them) → counts → wrench (SI).
static void BM_DecodeRdtRecords(benchmark::State& state) {
  std::mt19937 rng(2);
  std::vector<std::uint8_t> bytes(40 * netft::kRecordBytes);
  for (std::size_t k = 0; k < 40; ++k) {
    netft::RdtRecord r;
    r.rdt_sequence = static_cast<std::uint32_t>(k + 1);
    for (auto& c : r.counts) c = static_cast<std::int32_t>(rng() % 2'000'000) - 1'000'000;
    netft::encode_record(r, bytes.data() + k * netft::kRecordBytes);
  }
  netft::RdtRecord r;
  Vector6d w;
  std::size_t i = 0;
  for (auto _ : state) {
    netft::decode_record(bytes.data() + (i % 40) * netft::kRecordBytes, r);
    for (int k = 0; k < 6; ++k) w[k] = r.counts[static_cast<std::size_t>(k)] * 1e-6;
    benchmark::DoNotOptimize(w);
    ++i;
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()));
}
BENCHMARK(BM_DecodeRdtRecords);

static void BM_DecodeDeclarativeSignals(benchmark::State& state) {
  CanSignal s[3];
  for (unsigned k = 0; k < 3; ++k) {
    s[k].start_bit = 7 + 16 * k;
    s[k].big_endian = true;
    s[k].scale = 0.1;
  }
  const std::uint8_t data[8] = {1, 2, 3, 4, 5, 6, 7, 8};
  for (auto _ : state) {
    double v = 0;
    for (const auto& sig : s) v += static_cast<double>(extract_raw(sig, data)) * sig.scale + sig.offset;
    benchmark::DoNotOptimize(v);
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()));
}
BENCHMARK(BM_DecodeDeclarativeSignals);

static void BM_ParseCandumpLine(benchmark::State& state) {
  const std::string line = "(1732184000.123456) vcan0 1F334455#1122334455667788";
  CanFrame f;
  std::string iface;
  for (auto _ : state) {
    auto e = parse_candump_line(line, f, iface);
    benchmark::DoNotOptimize(e);
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()));
}
BENCHMARK(BM_ParseCandumpLine);

static void BM_FormatCandumpLine(benchmark::State& state) {
  CanFrame f;
  parse_frame_text("1F334455#1122334455667788", f);
  f.t_ns = 1732184000123456000LL;
  for (auto _ : state) {
    auto s = format_candump_line(f, "vcan0");
    benchmark::DoNotOptimize(s);
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()));
}
BENCHMARK(BM_FormatCandumpLine);

// One UR map sample (12 entries) from a register image.
static void BM_DecodeUrRegisters(benchmark::State& state) {
  const RegisterMap m = ur_register_map();
  std::vector<std::uint16_t> img(410, 1234);
  for (auto _ : state) {
    double sum = 0;
    for (const auto& e : m.entries)
      sum += decode_entry(e, &img[e.address],
                          e.turns_address >= 0 ? static_cast<std::int16_t>(img[static_cast<std::size_t>(e.turns_address)]) : 0);
    benchmark::DoNotOptimize(sum);
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()));
}
BENCHMARK(BM_DecodeUrRegisters);

BENCHMARK_MAIN();
