#!/usr/bin/env python3
"""An independent Robotiq FT 300 for hil's tests, written from Robotiq's manual with Python's
struct module (nothing of hil's codec): opens a pseudo-terminal, prints the path of its slave side,
logs every Modbus request it gets as a line on stdout ("request <slave> <fc> <address> <count>"),
answers FC03 on the identity and wrench registers, and answers FC16 0x0200 to register 410 with its
echo followed by `frames` stream frames (Fx counts + frame number, the others as given).

    ft300_sensor.py FRAMES FX FY FZ MX MY MZ      (counts: N x 100, N·m x 1000)
"""
import os
import select
import struct
import sys
import tty


def crc(data):
    # Modbus CRC-16 as the Modbus over serial line specification (§6.2.2) writes it.
    value = 0xFFFF
    for byte in data:
        value ^= byte
        for _ in range(8):
            lsb = value & 1
            value >>= 1
            if lsb:
                value ^= 0xA001
    return value


def with_crc(pdu):
    return pdu + struct.pack("<H", crc(pdu))


frames = int(sys.argv[1])
counts = [int(v) for v in sys.argv[2:8]]
registers = {180 + i: c & 0xFFFF for i, c in enumerate(counts)}
registers.update({500: 0x4654, 501: 0x5302, 502: 0x0007})  # "FTS" 2.0.7
registers.update({510: 0x5059, 511: 0x5400, 512: 4242, 513: 0, 514: 2024})  # "PYT-4242"
master, slave = os.openpty()
tty.setraw(slave)
print(os.ttyname(slave), flush=True)
buffer = b""
while True:
    select.select([master], [], [])
    buffer += os.read(master, 256)
    while len(buffer) >= 8:
        length = 9 + buffer[6] if buffer[1] == 16 and len(buffer) >= 7 else 8
        if len(buffer) < length:
            break
        request, buffer = buffer[:length], buffer[length:]
        if crc(request[:-2]) != struct.unpack("<H", request[-2:])[0]:
            print("bad crc", flush=True)
            buffer = b""
            break
        slave_id, fc, address, count = struct.unpack(">BBHH", request[:6])
        print("request %d %d %d %d" % (slave_id, fc, address, count), flush=True)
        if fc == 3:
            if all(address + k in registers for k in range(count)):
                values = [registers[address + k] for k in range(count)]
                os.write(master, with_crc(struct.pack(">BBB%dH" % count, slave_id, 3, 2 * count, *values)))
            else:
                os.write(master, with_crc(bytes([slave_id, 0x83, 0x02])))
        elif fc == 16 and address == 410 and request[7:9] == b"\x02\x00":
            os.write(master, with_crc(request[:6]))
            for k in range(1, frames + 1):
                frame = struct.pack("<BB6h", 0x20, 0x4E, counts[0] + k, *counts[1:])
                os.write(master, frame + struct.pack("<H", crc(frame)))
        else:
            os.write(master, with_crc(bytes([slave_id, fc | 0x80, 0x01])))
