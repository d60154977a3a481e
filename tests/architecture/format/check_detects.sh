#!/usr/bin/env bash
# architecture.format_detects: the formatting check can fail. In a temporary folder holding a copy
# of the repository's .clang-format, tools/format.sh --check must reject a misformatted snippet
# (exit 1, naming it), accept a formatted one (exit 0), and after tools/format.sh FILE the
# misformatted one must pass and keep its include order.
#   bash tests/architecture/format/check_detects.sh
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/../../.." && pwd)"
format="$root/tools/format.sh"
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
cp "$root/.clang-format" "$tmp/.clang-format"

fail() { echo "FAIL: $*" >&2; exit 1; }

# Formatted: the tree's habits (include order kept, `public:` one space in, `T* p`, short ifs
# and functions on one line, `}  // namespace`).
cat >"$tmp/good.cpp" <<'EOF'
#include <vector>
#include <map>

namespace hil::sample {

class Counter {
 public:
  explicit Counter(int* sink) : sink_(sink) {}
  int value() const { return n_; }
  void add(int k) {
    if (k < 0) return;
    n_ += k;
    if (sink_) *sink_ = n_;
  }

 private:
  int* sink_ = nullptr;
  int n_ = 0;
};

}  // namespace hil::sample
EOF

# Misformatted: the same code with the usual slips of a newcomer.
cat >"$tmp/bad.cpp" <<'EOF'
#include <vector>
#include <map>

namespace hil::sample {

class Counter
{
public:
    explicit Counter(int *sink) : sink_(sink) {}
    int value() const {return n_;}
    void add(int k)
    {
        if(k<0) return;
        n_+=k;
        if (sink_) *sink_ = n_;
    }
private:
    int *sink_ = nullptr;
    int n_ = 0;
};

}
EOF

set +e
out="$(bash "$format" --check "$tmp/bad.cpp" 2>&1)"
rc=$?
set -e
echo "$out"
[[ $rc -eq 1 ]] || fail "format.sh --check on a misformatted file exited $rc, expected 1"
grep -q 'bad\.cpp' <<<"$out" || fail "format.sh --check did not name the misformatted file"

set +e
out="$(bash "$format" --check "$tmp/good.cpp" 2>&1)"
rc=$?
set -e
echo "$out"
[[ $rc -eq 0 ]] || fail "format.sh --check on a formatted file exited $rc, expected 0"

bash "$format" "$tmp/bad.cpp"
bash "$format" --check "$tmp/bad.cpp" || fail "format.sh left bad.cpp unformatted"
cmp -s "$tmp/bad.cpp" "$tmp/good.cpp" || { diff "$tmp/good.cpp" "$tmp/bad.cpp" >&2 || true; fail "format.sh did not turn bad.cpp into good.cpp"; }
echo "format check detects misformatted code: ok"
