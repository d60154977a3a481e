#!/usr/bin/env bash
# check_needed.sh MODULE PROBE: MODULE's dynamic NEEDED entries name no Fast DDS (fastrtps,
# fastcdr) and no libmodbus; PROBE (the `hil` executable) must name both, or the check itself
# would be blind (readelf missing, a changed soname).
set -euo pipefail
module=$1
probe=$2
forbidden='libfastrtps|libfastcdr|libmodbus'
needed() { readelf -d "$1" | sed -n 's/.*(NEEDED).*\[\(.*\)\]/\1/p'; }
probe_hits=$(needed "$probe" | grep -cE "$forbidden" || true)
if ((probe_hits < 3)); then
  echo "check_needed: the probe $probe names $probe_hits of Fast DDS, Fast CDR and libmodbus; expected all 3:" >&2
  needed "$probe" >&2
  exit 2
fi
if hits=$(needed "$module" | grep -E "$forbidden"); then
  echo "check_needed: $module needs the bus or the devices:" >&2
  echo "$hits" >&2
  exit 1
fi
echo "check_needed: $(basename "$module") needs $(needed "$module" | tr '\n' ' ')"
echo "check_needed: no Fast DDS, no libmodbus"
