#!/usr/bin/python3
"""vcan harness test (b), run inside the guest (or on a host with SocketCAN) by run-in-vm.sh.

python-can (Debian's python3-can 4.1, for /usr/bin/python3) sends and receives on vcan0
through its socketcan interface: classic frames, an extended id, a kernel id filter, and a
CAN FD frame with 12 data bytes and bit-rate switch.
"""
import sys

import can

TIMEOUT = 10.0  # seconds; TCG guests are slow


def check(cond, what):
    if not cond:
        print(f"FAIL: {what}", file=sys.stderr)
        sys.exit(1)


def main():
    print(f"python-can {can.__version__}")
    with can.Bus(interface="socketcan", channel="vcan0", fd=True) as tx, \
         can.Bus(interface="socketcan", channel="vcan0", fd=True) as rx:
        sent = can.Message(arbitration_id=0x123, data=bytes.fromhex("DEADBEEF"),
                           is_extended_id=False)
        tx.send(sent)
        got = rx.recv(TIMEOUT)
        check(got is not None, "no classic frame received")
        check(got.arbitration_id == 0x123 and not got.is_extended_id, f"id of {got}")
        check(bytes(got.data) == sent.data, f"data of {got}")
        check(got.channel == "vcan0", f"channel of {got}")

        ext = can.Message(arbitration_id=0x1ABCDEF0, data=b"\x01\x02", is_extended_id=True)
        tx.send(ext)
        got = rx.recv(TIMEOUT)
        check(got is not None and got.is_extended_id and got.arbitration_id == 0x1ABCDEF0,
              f"extended frame: {got}")

        # Kernel-side filter (CAN_RAW_FILTER): only 0x200..0x20F reach rx.
        rx.set_filters([{"can_id": 0x200, "can_mask": 0x7F0, "extended": False}])
        tx.send(can.Message(arbitration_id=0x100, data=b"\xAA", is_extended_id=False))
        tx.send(can.Message(arbitration_id=0x205, data=b"\xBB", is_extended_id=False))
        got = rx.recv(TIMEOUT)
        check(got is not None and got.arbitration_id == 0x205, f"filtered frame: {got}")
        rx.set_filters(None)

        fd = can.Message(arbitration_id=0x456, data=bytes(range(12)), is_fd=True,
                         bitrate_switch=True, is_extended_id=False)
        tx.send(fd)
        got = rx.recv(TIMEOUT)
        check(got is not None and got.is_fd and got.bitrate_switch, f"CAN FD frame: {got}")
        check(bytes(got.data) == fd.data and got.dlc == 12, f"CAN FD data: {got}")
        check(rx.recv(0.2) is None, "unexpected extra frame")
    print("PASS: python-can send/receive on vcan0 (classic, extended, filter, CAN FD)")


if __name__ == "__main__":
    main()
