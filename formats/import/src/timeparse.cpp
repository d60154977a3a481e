#include <hil/import/timeparse.hpp>

#include <fmt/format.h>

#include <stdexcept>

namespace hil::import {

std::int64_t days_from_civil(std::int64_t y, unsigned m, unsigned d) {
  y -= m <= 2;
  const std::int64_t era = (y >= 0 ? y : y - 399) / 400;
  const auto yoe = static_cast<unsigned>(y - era * 400);
  const unsigned doy = (153 * (m + (m > 2 ? -3 : 9)) + 2) / 5 + d - 1;
  const unsigned doe = yoe * 365 + yoe / 4 - yoe / 100 + doy;
  return era * 146097 + static_cast<std::int64_t>(doe) - 719468;
}

namespace {

void civil_from_days(std::int64_t z, std::int64_t& y, unsigned& m, unsigned& d) {
  z += 719468;
  const std::int64_t era = (z >= 0 ? z : z - 146096) / 146097;
  const auto doe = static_cast<unsigned>(z - era * 146097);
  const unsigned yoe = (doe - doe / 1460 + doe / 36524 - doe / 146096) / 365;
  const unsigned doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
  const unsigned mp = (5 * doy + 2) / 153;
  d = doy - (153 * mp + 2) / 5 + 1;
  m = mp < 10 ? mp + 3 : mp - 9;
  y = static_cast<std::int64_t>(yoe) + era * 400 + (m <= 2);
}

unsigned days_in_month(std::int64_t y, unsigned m) {
  static const unsigned dm[] = {31, 28, 31, 30, 31, 30, 31, 31, 30, 31, 30, 31};
  const bool leap = (y % 4 == 0 && y % 100 != 0) || y % 400 == 0;
  return m == 2 && leap ? 29 : dm[m - 1];
}

}  // namespace

void check_datetime_pattern(const std::string& p) {
  std::string seen;
  for (std::size_t i = 0; i < p.size(); ++i) {
    if (p[i] != '%') continue;
    if (i + 1 == p.size()) throw std::invalid_argument("pattern ends with a lone '%'");
    const char c = p[++i];
    if (c == '%') continue;
    if (std::string("YmdHMSf").find(c) == std::string::npos)
      throw std::invalid_argument(fmt::format("unknown directive %{} (known: %Y %m %d %H %M %S %f %%)", c));
    if (seen.find(c) != std::string::npos) throw std::invalid_argument(fmt::format("%{} appears twice", c));
    seen += c;
  }
  for (char c : std::string("YmdHMS"))
    if (seen.find(c) == std::string::npos) throw std::invalid_argument(fmt::format("pattern lacks %{}", c));
}

std::optional<std::int64_t> parse_datetime_us(std::string_view s, const std::string& p, std::string* why) {
  auto fail = [&](std::size_t at, const std::string& what) -> std::optional<std::int64_t> {
    if (why) *why = fmt::format("expected {} at character {} (pattern '{}')", what, at + 1, p);
    return std::nullopt;
  };
  std::int64_t Y = 0;
  unsigned mo = 0, d = 0, H = 0, Mi = 0, S = 0;
  std::int64_t frac_us = 0;
  std::size_t k = 0;
  auto digits = [&](std::size_t min, std::size_t max, std::int64_t& v, std::size_t& n) {
    v = 0;
    n = 0;
    while (n < max && k < s.size() && s[k] >= '0' && s[k] <= '9') v = v * 10 + (s[k++] - '0'), ++n;
    return n >= min;
  };
  for (std::size_t i = 0; i < p.size(); ++i) {
    const std::size_t at = k;
    if (p[i] != '%' || (i + 1 < p.size() && p[i + 1] == '%')) {
      if (p[i] == '%') ++i;
      if (k >= s.size() || s[k] != p[i]) return fail(at, fmt::format("'{}'", p[i]));
      ++k;
      continue;
    }
    const char c = p[++i];
    std::int64_t v = 0;
    std::size_t n = 0;
    switch (c) {
      case 'Y':
        if (!digits(4, 4, v, n)) return fail(at, "a 4-digit year");
        Y = v;
        break;
      case 'm':
        if (!digits(1, 2, v, n) || v < 1 || v > 12) return fail(at, "a month 01..12");
        mo = static_cast<unsigned>(v);
        break;
      case 'd':
        if (!digits(1, 2, v, n) || v < 1 || v > 31) return fail(at, "a day 01..31");
        d = static_cast<unsigned>(v);
        break;
      case 'H':
        if (!digits(1, 2, v, n) || v > 23) return fail(at, "an hour 00..23");
        H = static_cast<unsigned>(v);
        break;
      case 'M':
        if (!digits(1, 2, v, n) || v > 59) return fail(at, "minutes 00..59");
        Mi = static_cast<unsigned>(v);
        break;
      case 'S':
        if (!digits(1, 2, v, n) || v > 59) return fail(at, "seconds 00..59");
        S = static_cast<unsigned>(v);
        break;
      case 'f': {
        if (!digits(1, 9, v, n)) return fail(at, "a fraction of a second (1 to 9 digits)");
        // Scale to nanoseconds, then round to microseconds.
        std::int64_t ns = v;
        for (std::size_t z = n; z < 9; ++z) ns *= 10;
        frac_us = (ns + 500) / 1000;
        break;
      }
      default: return fail(at, "a valid pattern");
    }
  }
  if (k != s.size()) return fail(k, "the end of the time text");
  if (d > days_in_month(Y, mo)) return fail(0, fmt::format("a valid date ({}-{:02} has {} days)", Y, mo, days_in_month(Y, mo)));
  const std::int64_t secs = days_from_civil(Y, mo, d) * 86400 + H * 3600 + Mi * 60 + S;
  return secs * 1000000 + frac_us;
}

std::optional<std::int64_t> parse_iso8601_utc_us(const std::string& t) {
  if (t.empty() || t.back() != 'Z') return std::nullopt;
  const std::string body = t.substr(0, t.size() - 1);
  const bool frac = body.find('.') != std::string::npos;
  return parse_datetime_us(body, frac ? "%Y-%m-%dT%H:%M:%S.%f" : "%Y-%m-%dT%H:%M:%S", nullptr);
}

std::string format_iso8601_utc_us(std::int64_t us) {
  std::int64_t days = us >= 0 ? us / 86400000000LL : -((-us + 86400000000LL - 1) / 86400000000LL);
  std::int64_t rem = us - days * 86400000000LL;
  std::int64_t y = 0;
  unsigned m = 0, d = 0;
  civil_from_days(days, y, m, d);
  const auto secs = rem / 1000000;
  return fmt::format("{:04}-{:02}-{:02}T{:02}:{:02}:{:02}.{:06}Z", y, m, d, secs / 3600, (secs / 60) % 60, secs % 60, rem % 1000000);
}

}  // namespace hil::import
