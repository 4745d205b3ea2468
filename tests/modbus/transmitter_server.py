#!/usr/bin/python3
"""A Modbus server emulating the bench's transmitters, for doorbench's Modbus tests.

Runs Debian's pymodbus 3.0.0 (python3-pymodbus) server, TCP on loopback or RTU on a serial
device (one end of a socat pty pair). Every unit id answers with the same register map,
computed afresh from time.monotonic() (CLOCK_MONOTONIC, the clock doorbench stamps samples
with) on every read, so a test can compare a decoded value with the formula at its time:

  force_N(t)   = 50 + 40 sin(2 pi 0.5 t)        load-cell transmitter
  angle_deg(t) = 5 sin(2 pi 0.2 t)              inclinometer
  rate_dps(t)  = 5 (2 pi 0.2) cos(2 pi 0.2 t)   gyroscope (the angle's derivative)

  address  type     content                 byte order (A = most significant byte)
  0-1      float32  force_N                 ABCD
  2-3      float32  force_N                 CDAB
  4-5      float32  force_N                 BADC
  6-7      float32  force_N                 DCBA
  8        int16    angle in 0.01 deg       AB
  9        int16    rate in 0.01 deg/s      AB
  10-11    int32    force in mN             ABCD
  12-13    int32    force in mN             CDAB
  14       uint16   angle in 0.01 deg + 10000  BA (bytes swapped)
  15-99    uint16   0
Holding and input registers hold the same map; reads past 99 get an exception reply
(illegal data address) from pymodbus itself.

Misbehaviour, counted over all requests since the start:
  --silent-after N --silent-for S   after request N, ignore requests for S seconds
  --exception-every K               every K-th request: exception reply "server device failure"
  --drop-every K                    every K-th request: close the connection without a reply (TCP)
  --bad-crc-every K                 every K-th reply: last CRC byte flipped (RTU)

Prints "PORT <n>" (TCP; bound to port 0, so tests do not collide) or "READY" (RTU) on
stdout once it serves.
"""
import argparse
import asyncio
import math
import struct
import sys
import time

from pymodbus.datastore import ModbusServerContext, ModbusSlaveContext
from pymodbus.datastore.store import BaseModbusDataBlock
from pymodbus.pdu import ModbusExceptions
from pymodbus.server.async_io import (
    ModbusConnectedRequestHandler,
    ModbusSerialServer,
    ModbusSingleRequestHandler,
    ModbusTcpServer,
)
from pymodbus.transaction import ModbusRtuFramer, ModbusSocketFramer

REGISTERS = 100


def force_N(t):
    return 50.0 + 40.0 * math.sin(2 * math.pi * 0.5 * t)


def angle_deg(t):
    return 5.0 * math.sin(2 * math.pi * 0.2 * t)


def rate_dps(t):
    return 5.0 * 2 * math.pi * 0.2 * math.cos(2 * math.pi * 0.2 * t)


def words(raw4, order):
    """Two registers of 4 big-endian bytes ABCD, rearranged to `order`."""
    index = {"A": 0, "B": 1, "C": 2, "D": 3}
    b = bytes(raw4[index[c]] for c in order)
    return [b[0] << 8 | b[1], b[2] << 8 | b[3]]


def register_map(t):
    regs = [0] * REGISTERS
    f = struct.pack(">f", force_N(t))
    for address, order in ((0, "ABCD"), (2, "CDAB"), (4, "BADC"), (6, "DCBA")):
        regs[address:address + 2] = words(f, order)
    regs[8] = struct.unpack(">H", struct.pack(">h", round(100 * angle_deg(t))))[0]
    regs[9] = struct.unpack(">H", struct.pack(">h", round(100 * rate_dps(t))))[0]
    mN = struct.pack(">i", round(1000 * force_N(t)))
    regs[10:12] = words(mN, "ABCD")
    regs[12:14] = words(mN, "CDAB")
    shifted = round(100 * angle_deg(t)) + 10000
    regs[14] = ((shifted & 0xFF) << 8) | (shifted >> 8)
    return regs


class LiveBlock(BaseModbusDataBlock):
    """Registers computed at the moment they are read."""

    def __init__(self):
        self.address = 0
        self.default_value = 0
        self.values = [0] * REGISTERS

    def validate(self, address, count=1):
        return 0 <= address and count >= 1 and address + count <= REGISTERS

    def getValues(self, address, count=1):
        return register_map(time.monotonic())[address:address + count]

    def setValues(self, address, values):
        pass


class Misbehaviour:
    def __init__(self, args):
        self.args = args
        self.requests = 0
        self.replies = 0
        self.silent_until = None

    def on_request(self):
        """What to do with the next request: 'answer', 'ignore', 'exception' or 'drop'."""
        a = self.args
        self.requests += 1
        n = self.requests
        now = time.monotonic()
        if a.silent_after and n == a.silent_after + 1:
            self.silent_until = now + a.silent_for
        if self.silent_until is not None and now < self.silent_until:
            return "ignore"
        if a.drop_every and n % a.drop_every == 0:
            return "drop"
        if a.exception_every and n % a.exception_every == 0:
            return "exception"
        return "answer"

    def corrupt_reply(self):
        self.replies += 1
        return bool(self.args.bad_crc_every) and self.replies % self.args.bad_crc_every == 0


MISBEHAVIOUR = None


class Behaviour:
    """Mixed into pymodbus' request handlers: the misbehaviour before its execute()."""

    def execute(self, request, *addr):
        action = MISBEHAVIOUR.on_request()
        if action == "ignore":
            return
        if action == "drop":
            self.transport.close()
            return
        if action == "exception":
            response = request.doException(ModbusExceptions.SlaveFailure)
            response.transaction_id = request.transaction_id
            response.unit_id = request.unit_id
            self.send(response, *addr)
            return
        super().execute(request, *addr)

    def _send_(self, data, *rest):
        if MISBEHAVIOUR.corrupt_reply():
            data = data[:-1] + bytes([data[-1] ^ 0xFF])
        super()._send_(data, *rest)


class TcpHandler(Behaviour, ModbusConnectedRequestHandler):
    pass


class SerialHandler(Behaviour, ModbusSingleRequestHandler):
    pass


async def main():
    global MISBEHAVIOUR
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--transport", choices=["tcp", "rtu"], default="tcp")
    parser.add_argument("--device", help="serial device (rtu)")
    parser.add_argument("--baud", type=int, default=115200)
    parser.add_argument("--units", default="1,2,3", help="unit ids that answer")
    parser.add_argument("--silent-after", type=int, default=0)
    parser.add_argument("--silent-for", type=float, default=0.0)
    parser.add_argument("--exception-every", type=int, default=0)
    parser.add_argument("--drop-every", type=int, default=0)
    parser.add_argument("--bad-crc-every", type=int, default=0)
    args = parser.parse_args()
    MISBEHAVIOUR = Misbehaviour(args)

    block = LiveBlock()
    slaves = {
        int(u): ModbusSlaveContext(hr=block, ir=block, zero_mode=True)
        for u in args.units.split(",")
    }
    context = ModbusServerContext(slaves=slaves, single=False)

    if args.transport == "tcp":
        server = ModbusTcpServer(context, framer=ModbusSocketFramer, address=("127.0.0.1", 0),
                                 handler=TcpHandler, ignore_missing_slaves=True)
        task = asyncio.create_task(server.serve_forever())
        await server.serving
        print("PORT", server.server.sockets[0].getsockname()[1], flush=True)
        await task
    else:
        server = ModbusSerialServer(context, framer=ModbusRtuFramer, port=args.device,
                                    baudrate=args.baud, handler=SerialHandler,
                                    ignore_missing_slaves=True)
        await server.start()
        print("READY", flush=True)
        await server.serve_forever()


if __name__ == "__main__":
    try:
        asyncio.run(main())
    except KeyboardInterrupt:
        sys.exit(0)
