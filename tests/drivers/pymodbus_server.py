"""A pymodbus TCP server on 127.0.0.1 (an independent Modbus implementation for the driver tests).

Usage: pymodbus_server.py ADDR=V1,V2,... [ADDR=...]   (holding registers, also served as input registers)
Prints the bound port on stdout, then serves until stdin closes.
"""
import asyncio
import logging
import sys

from pymodbus.datastore import ModbusSequentialDataBlock, ModbusServerContext, ModbusSlaveContext
from pymodbus.server.async_io import ModbusTcpServer


def registers(args):
    values = [0] * 1024
    for arg in args:
        addr, vals = arg.split("=")
        for i, v in enumerate(vals.split(",")):
            values[int(addr) + i] = int(v)
    return values


async def main():
    logging.disable(logging.CRITICAL)
    values = registers(sys.argv[1:])
    slave = ModbusSlaveContext(hr=ModbusSequentialDataBlock(0, list(values)),
                               ir=ModbusSequentialDataBlock(0, list(values)), zero_mode=True)
    context = ModbusServerContext(slaves=slave, single=True)
    server = ModbusTcpServer(context, address=("127.0.0.1", 0), allow_reuse_address=True)
    task = asyncio.ensure_future(server.serve_forever())
    await server.serving
    print(server.server.sockets[0].getsockname()[1], flush=True)
    loop = asyncio.get_running_loop()
    await loop.run_in_executor(None, sys.stdin.read)
    await server.shutdown()
    task.cancel()


asyncio.run(main())
