#!/usr/bin/env python3
"""An independent Net F/T RDT peer for hil's tests, written from ATI's published layout with
Python's struct module (nothing of hil's codec): answers on 127.0.0.1, prints its port, logs every
request it gets as a line on stdout ("request <header> <command> <count>"), and answers a start
request (0x0002 or 0x0003) with `records` records packed `per_datagram` to a datagram:
rdt_sequence 1.., ft_sequence 1000 + 3 per record, status and counts as given.

    netft_box.py RECORDS PER_DATAGRAM STATUS FX FY FZ TX TY TZ
"""
import socket
import struct
import sys

records, per_datagram, status = int(sys.argv[1]), int(sys.argv[2]), int(sys.argv[3], 0)
counts = [int(v) for v in sys.argv[4:10]]
s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
s.bind(("127.0.0.1", 0))
print(s.getsockname()[1], flush=True)
while True:
    data, peer = s.recvfrom(64)
    if len(data) != 8:
        print("bad request of %d bytes" % len(data), flush=True)
        continue
    header, command, count = struct.unpack("!HHI", data)
    print("request 0x%04x 0x%04x %d" % (header, command, count), flush=True)
    if header != 0x1234 or command not in (0x0002, 0x0003):
        continue
    seq = 0
    while seq < records:
        chunk = b""
        for _ in range(min(per_datagram, records - seq)):
            seq += 1
            # Counts change with the record so that each one is told apart: Fx + sequence.
            chunk += struct.pack("!IIIiiiiii", seq, 1000 + 3 * seq, status, counts[0] + seq, *counts[1:])
        s.sendto(chunk, peer)
