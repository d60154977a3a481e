#pragma once
/// \file CAN frames and their pure codecs: the kernel's `struct can_frame`/`canfd_frame` byte
/// layout, validation, id filters and error-frame decoding (linux/can/error.h). No I/O here.
#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>

namespace hil::drivers {

/// Where a receive timestamp came from.
enum class StampSource : std::uint8_t { none, software, hardware };

/// One classic or CAN FD frame, or an error frame, as the application sees it.
struct CanFrame {
  std::uint32_t id = 0;       ///< 11-bit or 29-bit identifier; error frames: the CAN_ERR_* class bits
  std::uint8_t len = 0;       ///< payload bytes (0..8 classic, 0..64 FD); RTR: the requested DLC
  std::uint8_t fd_flags = 0;  ///< CAN FD flags nibble (BRS 0x1, ESI 0x2, FDF 0x4, ...), as candump prints it
  bool extended = false;      ///< 29-bit identifier
  bool rtr = false;           ///< remote transmission request (classic only)
  bool error = false;         ///< error frame (CAN_ERR_FLAG)
  bool fd = false;            ///< CAN FD frame (CANFD_MTU on the socket)
  StampSource stamp = StampSource::none;
  std::int64_t t_ns = 0;  ///< receive time, CLOCK_REALTIME ns since the epoch (0 = unknown)
  std::array<std::uint8_t, 64> data{};
};

/// Same id, kind, length, flags and payload bytes (timestamps ignored).
bool same_frame(const CanFrame& a, const CanFrame& b) noexcept;

inline constexpr std::uint32_t kCanEffFlag = 0x80000000U;
inline constexpr std::uint32_t kCanRtrFlag = 0x40000000U;
inline constexpr std::uint32_t kCanErrFlag = 0x20000000U;
inline constexpr std::uint32_t kCanSffMask = 0x000007FFU;
inline constexpr std::uint32_t kCanEffMask = 0x1FFFFFFFU;
inline constexpr std::uint32_t kCanErrMask = 0x1FFFFFFFU;
inline constexpr std::size_t kCanMtu = 16;    ///< sizeof(struct can_frame)
inline constexpr std::size_t kCanFdMtu = 72;  ///< sizeof(struct canfd_frame)

/// The kernel's `can_id` word: identifier plus EFF/RTR/ERR flags.
std::uint32_t kernel_can_id(const CanFrame& f) noexcept;

/// True for the payload lengths a CAN FD frame can have (0..8, 12, 16, 20, 24, 32, 48, 64).
bool valid_fd_length(unsigned len) noexcept;

/// Why a frame is not valid, or nullptr when it is (id range, length, RTR/FD/error combinations).
const char* frame_problem(const CanFrame& f) noexcept;

enum class CanCodecStatus : std::uint8_t { ok, bad_size, bad_length, bad_id };
const char* to_string(CanCodecStatus s) noexcept;

/// Writes the kernel layout (host-endian can_id, len, flags, data) into `out`.
/// \returns kCanMtu for classic/error frames, kCanFdMtu for FD frames, 0 if the frame is not valid.
std::size_t encode_kernel_frame(const CanFrame& f, std::span<std::uint8_t, kCanFdMtu> out) noexcept;

/// Reads a frame in the kernel layout (16 bytes classic, 72 bytes FD). Real-time safe, no allocation.
/// Leaves t_ns/stamp untouched.
CanCodecStatus decode_kernel_frame(std::span<const std::uint8_t> in, CanFrame& out) noexcept;

/// A kernel-style receive filter (`struct can_filter`): a frame passes when
/// `(kernel_can_id & mask) == (id & mask)`; `inverted` passes the others (CAN_INV_FILTER).
struct CanFilter {
  std::uint32_t id = 0;
  std::uint32_t mask = 0;
  bool inverted = false;
  /// Exactly this identifier, data and RTR frames, of the given id kind.
  static CanFilter exact(std::uint32_t id, bool extended = false) noexcept;
  /// Every id with `(id & mask) == (base & mask)` (id bits only), of the given id kind.
  static CanFilter masked(std::uint32_t base, std::uint32_t id_mask, bool extended = false) noexcept;
};
/// Kernel semantics: no filters = everything; error frames are not subject to filters.
bool passes(std::span<const CanFilter> filters, const CanFrame& f) noexcept;

/// An error frame (CAN_ERR_FLAG) decoded after linux/can/error.h.
struct CanErrorInfo {
  std::uint32_t classes = 0;  ///< CAN_ERR_* class bits
  bool tx_timeout = false;
  bool lost_arbitration = false;
  int lost_arbitration_bit = -1;  ///< -1 = unspecified
  bool controller = false;        ///< controller problem (details below)
  bool rx_overflow = false, tx_overflow = false;
  bool warning = false;         ///< error-warning level reached (rx or tx)
  bool error_passive = false;   ///< error-passive (rx or tx)
  bool back_to_active = false;  ///< recovered to error-active
  bool protocol = false;
  std::uint8_t protocol_type = 0, protocol_location = 0;
  bool transceiver = false;
  bool no_ack = false;
  bool bus_off = false;
  bool bus_error = false;
  bool restarted = false;
  int tx_error_count = -1, rx_error_count = -1;  ///< -1 = not given (CAN_ERR_CNT)
};
CanErrorInfo decode_error_frame(const CanFrame& f) noexcept;
/// Readable summary, e.g. "bus-off", "error-passive (rx), tx errors 130".
std::string describe(const CanErrorInfo& e);

/// Builders for the fakes and tests.
CanFrame make_error_frame(std::uint32_t classes, std::array<std::uint8_t, 8> data = {}) noexcept;
inline constexpr std::uint32_t kErrTxTimeout = 0x001, kErrLostArb = 0x002, kErrCrtl = 0x004, kErrProt = 0x008, kErrTrx = 0x010,
                               kErrAck = 0x020, kErrBusOff = 0x040, kErrBusError = 0x080, kErrRestarted = 0x100, kErrCnt = 0x200;
inline constexpr std::uint8_t kErrCrtlRxOverflow = 0x01, kErrCrtlTxOverflow = 0x02, kErrCrtlRxWarning = 0x04, kErrCrtlTxWarning = 0x08,
                              kErrCrtlRxPassive = 0x10, kErrCrtlTxPassive = 0x20, kErrCrtlActive = 0x40;

}  // namespace hil::drivers
