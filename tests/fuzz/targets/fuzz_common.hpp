#pragma once
// Shared by the libFuzzer targets: the property every target checks is "a value or the project's
// own error type". Anything else a reader lets escape (yaml-cpp, std::out_of_range, ...) is a
// finding: it would reach the user as a bare what() without file, line or field.
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <string>
#include <typeinfo>

namespace hil::fuzz {

[[noreturn]] inline void unexpected(const char* target, const std::exception* e) {
  std::fprintf(stderr, "%s: unexpected exception %s: %s\n", target, e ? typeid(*e).name() : "(not std::exception)", e ? e->what() : "");
  std::abort();
}

[[noreturn]] inline void violated(const char* target, const char* property) {
  std::fprintf(stderr, "%s: property violated: %s\n", target, property);
  std::abort();
}

/// Runs `parse`: returning, or throwing the project's error type `Expected`, is an answer; any other
/// exception is a finding.
template <class Expected, class Parse>
void answers_or(const char* target, Parse&& parse) {
  try {
    parse();
  } catch (const Expected&) {
  } catch (const std::exception& e) {
    unexpected(target, &e);
  } catch (...) {
    unexpected(target, nullptr);
  }
}

/// Input bytes consumed from the front (for targets whose first bytes choose a configuration).
class Bytes {
 public:
  Bytes(const std::uint8_t* data, std::size_t size) : p_(data), n_(size) {}
  std::size_t left() const noexcept { return n_; }
  std::uint8_t u8() noexcept { return n_ ? (--n_, *p_++) : 0; }
  std::uint16_t u16() noexcept { return static_cast<std::uint16_t>(u8() << 8 | u8()); }
  std::uint32_t u32() noexcept { return static_cast<std::uint32_t>(u16()) << 16 | u16(); }
  /// The rest of the input as text.
  std::string rest() {
    std::string s(reinterpret_cast<const char*>(p_), n_);
    p_ += n_;
    n_ = 0;
    return s;
  }

 private:
  const std::uint8_t* p_;
  std::size_t n_;
};

}  // namespace hil::fuzz
