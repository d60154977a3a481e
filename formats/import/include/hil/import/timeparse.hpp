#pragma once
/// \file Time text of imported data: datetime patterns and UTC ISO 8601, as integer microseconds
/// since 1970-01-01T00:00:00 (a double would lose the microseconds of a 2023 timestamp's seconds).
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

namespace hil::import {

/// Checks a strptime-like pattern: %Y %m %d %H %M %S (each once, all required), %f (fraction of a
/// second, 1 to 9 digits, optional), %% and literal characters. \throws std::invalid_argument.
void check_datetime_pattern(const std::string& pattern);

/// Parses `text` with `pattern` into microseconds since 1970 on the same clock (no time zone).
/// Fractions finer than 1 us are rounded to the nearest us. On failure returns nullopt and sets
/// `why` (what was expected at which character).
std::optional<std::int64_t> parse_datetime_us(std::string_view text, const std::string& pattern, std::string* why);

/// `2026-11-21T10:00:00Z` or with a fraction of 1..9 digits. nullopt if not that form.
std::optional<std::int64_t> parse_iso8601_utc_us(const std::string& text);

/// Microseconds since 1970 (UTC) -> `2023-09-20T16:40:52.540797Z`.
std::string format_iso8601_utc_us(std::int64_t us_since_epoch);

/// Days since 1970-01-01 of a proleptic Gregorian date (H. Hinnant's algorithm).
std::int64_t days_from_civil(std::int64_t y, unsigned m, unsigned d);

}  // namespace hil::import
