"""Reads holding registers with pymodbus' client and prints them space-separated, one line per range.

Usage: pymodbus_client.py PORT ADDR:COUNT [ADDR:COUNT ...]
"""
import sys

from pymodbus.client import ModbusTcpClient

client = ModbusTcpClient("127.0.0.1", port=int(sys.argv[1]), timeout=5)
if not client.connect():
    print("connect failed", file=sys.stderr)
    sys.exit(2)
for spec in sys.argv[2:]:
    addr, count = (int(x) for x in spec.split(":"))
    rr = client.read_holding_registers(addr, count, slave=1)
    if rr.isError():
        print(f"error {rr}", file=sys.stderr)
        sys.exit(3)
    print(" ".join(str(v) for v in rr.registers), flush=True)
client.close()
