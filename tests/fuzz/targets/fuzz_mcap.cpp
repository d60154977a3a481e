// MCAP reader (formats/mcap): read_bytes (strict) and recover_bytes (a file cut or damaged at its
// end) on arbitrary bytes. Both answer with the file or a FormatError; a recovery never keeps more
// messages than it says, and on a file the strict reader accepts it reads the same messages.
#include "fuzz_common.hpp"
#include <hil/error/error.hpp>
#include <hil/mcap/mcap.hpp>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string bytes(reinterpret_cast<const char*>(data), size);
  std::size_t strict_messages = 0;
  bool strict_ok = false;
  hil::fuzz::answers_or<hil::error::FormatError>("fuzz_mcap", [&] {
    strict_messages = hil::mcap::read_bytes(bytes, "fuzz.mcap").messages.size();
    strict_ok = true;
  });
  hil::fuzz::answers_or<hil::error::FormatError>("fuzz_mcap", [&] {
    hil::mcap::Recovery r;
    const auto f = hil::mcap::recover_bytes(bytes, "fuzz.mcap", r);
    if (r.messages != f.messages.size() || r.bytes_read > r.bytes_total || r.bytes_total != size)
      hil::fuzz::violated("fuzz_mcap", "the recovery's counts disagree with what it returned");
    if (strict_ok && (!r.complete || f.messages.size() != strict_messages))
      hil::fuzz::violated("fuzz_mcap", "a file the strict reader accepts is not read whole by the recovery");
  });
  return 0;
}
