#!/usr/bin/env bash
# The C++ sources' formatting, by clang-format with the repository's .clang-format:
#   bash tools/format.sh                   format every tracked C++ file in place
#   bash tools/format.sh --check           list the files that are not formatted: exit 1 if any, 0 if none
#   bash tools/format.sh [--check] FILE... the same on these files only (clang-format finds the
#                                          .clang-format next to each file or in a parent folder)
# Tracked C++ files: git ls-files '*.cpp' '*.hpp' '*.h' (find when there is no .git), less examples/
# and tests/fuzz/{corpus,regressions} (data, not code). clang-format: $CLANG_FORMAT, else
# clang-format, else clang-format-14 (Debian 12: apt-get install clang-format). The style is tuned
# for clang-format 14; another major version may format a few constructs differently.
set -euo pipefail

usage() { echo "usage: bash tools/format.sh [--check] [FILE...]" >&2; exit 2; }

check=0
files=()
for arg in "$@"; do
  case "$arg" in
    --check) check=1 ;;
    -h|--help) usage ;;
    -*) echo "format.sh: unknown option $arg" >&2; usage ;;
    *)
      [[ -f "$arg" ]] || { echo "format.sh: no such file: $arg" >&2; exit 2; }
      # Absolute, since the script moves to the repository root below.
      files+=("$(cd "$(dirname "$arg")" && pwd)/$(basename "$arg")") ;;
  esac
done

root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"

cf="${CLANG_FORMAT:-}"
if [[ -z "$cf" ]]; then
  for c in clang-format clang-format-14; do
    if command -v "$c" >/dev/null 2>&1; then cf="$c"; break; fi
  done
fi
if [[ -z "$cf" ]] || ! command -v "$cf" >/dev/null 2>&1; then
  echo "format.sh: clang-format not found (tried ${CLANG_FORMAT:-clang-format, clang-format-14});" \
       "install it: apt-get install clang-format (Debian 12: clang-format 14)" >&2
  exit 2
fi
version="$("$cf" --version | sed -n 's/.*clang-format version \([0-9][0-9]*\).*/\1/p')"
if [[ -n "$version" && "$version" != 14 ]]; then
  echo "format.sh: note: $cf is version $version; .clang-format is tuned for clang-format 14" >&2
fi

if ((${#files[@]} == 0)); then
  excluded='^(examples/|tests/fuzz/corpus/|tests/fuzz/regressions/|build[^/]*/)'
  if git -C "$root" rev-parse --is-inside-work-tree >/dev/null 2>&1 && [[ -e "$root/.git" ]]; then
    # Tracked files that still exist (a deleted but not yet staged file is listed by ls-files).
    while IFS= read -r f; do
      [[ -f "$f" ]] && files+=("$f")
    done < <(git -C "$root" ls-files -- '*.cpp' '*.hpp' '*.h' | grep -Ev "$excluded" || true)
  else
    while IFS= read -r f; do
      files+=("$f")
    done < <(find . -type f \( -name '*.cpp' -o -name '*.hpp' -o -name '*.h' \) -not -path './.git/*' \
               | sed 's|^\./||' | grep -Ev "$excluded" | LC_ALL=C sort || true)
  fi
  if ((${#files[@]} == 0)); then echo "format.sh: no C++ files found under $root" >&2; exit 2; fi
fi

if ((check == 0)); then
  printf '%s\0' "${files[@]}" | xargs -0 -n 32 -P "$(nproc 2>/dev/null || echo 2)" "$cf" -i --style=file
  echo "format.sh: formatted ${#files[@]} files"
  exit 0
fi

# --check: clang-format --dry-run --Werror reports each unformatted file as
# FILE:LINE:COL: error: code should be clang-formatted [-Wclang-format-violations];
# anything else on stderr with a failure (a bad .clang-format, an unreadable file) is an error.
out="$(mktemp)"
trap 'rm -f "$out"' EXIT
status=0
printf '%s\0' "${files[@]}" \
  | xargs -0 -n 32 -P "$(nproc 2>/dev/null || echo 2)" "$cf" --dry-run --Werror --ferror-limit=1 --style=file \
      >/dev/null 2>"$out" || status=$?
bad="$(grep -E ': error: code should be clang-formatted \[-Wclang-format-violations\]$' "$out" \
         | sed -E 's/:[0-9]+:[0-9]+: error: code should be clang-formatted.*$//' | LC_ALL=C sort -u || true)"
if ((status != 0)) && [[ -z "$bad" ]]; then
  cat "$out" >&2
  echo "format.sh: $cf failed (exit $status) without naming an unformatted file" >&2
  exit 2
fi
if [[ -n "$bad" ]]; then
  echo "format.sh: $(printf '%s\n' "$bad" | wc -l) of ${#files[@]} files are not formatted (fix: bash tools/format.sh):"
  printf '%s\n' "$bad" | sed "s|^$root/||; s|^|  |"
  exit 1
fi
echo "format.sh: all ${#files[@]} files are formatted"
