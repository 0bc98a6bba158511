#!/usr/bin/env python3
"""An independent Modbus RTU spindle VFD built on pymodbus, for klar's driver tests.

It emulates one of klar's VFD register maps from their written definitions (the Delta
communication map from the Delta manuals, or the generic map in docs/modbus.md), with a
linear speed ramp. Two pseudo-terminal pairs are bridged by a relay: pymodbus serves on
one, the client under test opens the other (its path is announced on stdout). The relay
can corrupt a response to exercise CRC handling.

Protocol on stdout: one JSON object per line.
  {"event": "ready", "port": "/dev/pts/N"}
  {"event": "write", "address": A, "values": [...]}        every register write accepted
  {"event": "rejected", "address": A, "count": N, "fc": F}  a request refused (exception)
  {"event": "state", ...}                                   answer to the "state" command
Commands on stdin, one per line: "state", "fault CODE", "silent 0|1", "corrupt N"
(corrupt the next N responses), "busy N" (answer the next N requests with exception 06,
server device busy), "quit". The peer exits when stdin closes or after
--max-seconds.
"""

import argparse
import asyncio
import json
import os
import select
import sys
import threading
import time
import tty

from pymodbus.constants import ExcCodes
from pymodbus.framer import FramerType
from pymodbus.server import ModbusSerialServer
from pymodbus.simulator import DataType, SimData, SimDevice

OUT_LOCK = threading.Lock()


def emit(obj):
    with OUT_LOCK:
        sys.stdout.write(json.dumps(obj) + "\n")
        sys.stdout.flush()


class Drive:
    """Speed ramp of the emulated VFD, in rpm."""

    def __init__(self, accel):
        self.accel = accel
        self.rpm = 0.0
        self.target = 0.0
        self.fault = 0
        self.t = time.monotonic()
        self.lock = threading.Lock()

    def advance(self):
        now = time.monotonic()
        dt = now - self.t
        self.t = now
        target = 0.0 if self.fault else self.target
        step = self.accel * dt
        if abs(target - self.rpm) <= step:
            self.rpm = target
        else:
            self.rpm += step if target > self.rpm else -step


class DeltaVfd:
    """Delta map: 2000H command, 2001H frequency (0.01 Hz), 2002H reset,
    2100H error, 2101H status, 2102H frequency command, 2103H output frequency, 2104H current."""

    def __init__(self, drive, rpm_per_hz):
        self.drive = drive
        self.rpm_per_hz = rpm_per_hz
        self.run = False
        self.reverse = False
        self.freq = 0  # 0.01 Hz

    def simdata(self):
        return [
            SimData(0x2000, count=3, values=0, datatype=DataType.REGISTERS),
            SimData(0x2100, count=5, values=0, datatype=DataType.REGISTERS, readonly=True),
        ]

    def write(self, address, value):
        if address == 0x2000:
            runbits = value & 0b11
            if runbits == 0b01:
                self.run = False
            elif runbits in (0b10, 0b11):
                self.run = True
            dirbits = (value >> 4) & 0b11
            if dirbits == 0b01:
                self.reverse = False
            elif dirbits == 0b10:
                self.reverse = True
            elif dirbits == 0b11:
                self.reverse = not self.reverse
        elif address == 0x2001:
            self.freq = value
        elif address == 0x2002:
            if value & 0b10:
                self.drive.fault = 0
                self.run = False
        self.update_target()

    def update_target(self):
        rpm = self.freq / 100.0 * self.rpm_per_hz
        self.drive.target = (-rpm if self.reverse else rpm) if self.run else 0.0

    def fill(self, regs, start):
        d = self.drive
        running = 0b11 if (self.run and not d.fault) else (0b01 if d.rpm != 0 else 0b00)
        direction = 0b11 if d.rpm < 0 or (d.rpm == 0 and self.reverse) else 0b00
        regs[0x2100 - start] = d.fault
        regs[0x2101 - start] = running | (direction << 3)
        regs[0x2102 - start] = self.freq
        regs[0x2103 - start] = int(round(abs(d.rpm) / self.rpm_per_hz * 100.0))
        regs[0x2104 - start] = 0


class GenericVfd:
    """Generic map (docs/modbus.md): 0 control (bit0 run, bit1 reverse, bit2 reset),
    1 speed setpoint (rpm), 2 status (bit0 running, bit1 reverse, bit3 fault),
    3 actual speed (rpm), 4 fault code."""

    def __init__(self, drive):
        self.drive = drive
        self.control = 0
        self.speed = 0

    def simdata(self):
        return [
            SimData(0, count=2, values=0, datatype=DataType.REGISTERS),
            SimData(2, count=3, values=0, datatype=DataType.REGISTERS, readonly=True),
        ]

    def write(self, address, value):
        if address == 0:
            self.control = value
            if value & 0b100:
                self.drive.fault = 0
        elif address == 1:
            self.speed = value
        run = bool(self.control & 1)
        rev = bool(self.control & 2)
        self.drive.target = (-self.speed if rev else self.speed) if run else 0.0

    def fill(self, regs, start):
        d = self.drive
        status = (1 if d.rpm != 0 or self.control & 1 else 0) | (2 if d.rpm < 0 else 0)
        status |= 8 if d.fault else 0
        regs[2 - start] = status
        regs[3 - start] = int(round(abs(d.rpm)))
        regs[4 - start] = d.fault


class Relay:
    """Copies bytes between the two pty masters; can corrupt responses."""

    def __init__(self, client_master, server_master):
        self.a = client_master
        self.b = server_master
        self.corrupt = 0
        self.silent = False
        self.lock = threading.Lock()

    def run(self):
        while True:
            try:
                ready, _, _ = select.select([self.a, self.b], [], [], 0.5)
            except (OSError, ValueError):
                return
            for fd in ready:
                try:
                    data = os.read(fd, 4096)
                except OSError:
                    data = b""
                if not data:
                    continue
                if fd == self.a:
                    with self.lock:
                        silent = self.silent
                    if not silent:
                        self.send(self.b, data)
                else:
                    with self.lock:
                        if self.corrupt > 0:
                            self.corrupt -= 1
                            data = data[:-1] + bytes([data[-1] ^ 0x5A])
                            emit({"event": "corrupted"})
                    self.send(self.a, data)

    @staticmethod
    def send(fd, data):
        try:
            os.write(fd, data)
        except OSError:
            pass


def make_pty():
    master, slave = os.openpty()
    tty.setraw(slave)
    return master, slave, os.ttyname(slave)


async def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--map", choices=["delta", "generic"], required=True)
    ap.add_argument("--unit", type=int, default=1)
    ap.add_argument("--rpm-per-hz", type=float, default=60.0)
    ap.add_argument("--accel", type=float, default=20000.0, help="rpm per second")
    ap.add_argument("--max-seconds", type=float, default=60.0)
    args = ap.parse_args()

    drive = Drive(args.accel)
    vfd = DeltaVfd(drive, args.rpm_per_hz) if args.map == "delta" else GenericVfd(drive)

    busy = {"left": 0}

    async def action(fc, start, address, count, regs, values):
        with drive.lock:
            if busy["left"] > 0:
                busy["left"] -= 1
                emit({"event": "busy", "fc": fc, "address": address})
                return ExcCodes.DEVICE_BUSY
            drive.advance()
            if values is not None:
                for i, v in enumerate(values):
                    vfd.write(address + i, int(v))
                emit({"event": "write", "fc": fc, "address": address, "values": [int(v) for v in values]})
            vfd.fill(regs, start)
        return None

    device = SimDevice(args.unit, simdata=vfd.simdata(), action=action)

    client_master, client_slave, client_path = make_pty()
    server_master, server_slave, server_path = make_pty()
    relay = Relay(client_master, server_master)
    threading.Thread(target=relay.run, daemon=True).start()

    def trace_pdu(sending, pdu):
        if sending and getattr(pdu, "exception_code", 0):
            emit({"event": "rejected", "fc": pdu.function_code & 0x7F, "code": int(pdu.exception_code)})
        return pdu

    server = ModbusSerialServer(
        device,
        framer=FramerType.RTU,
        port=server_path,
        baudrate=115200,
        parity="N",
        trace_pdu=trace_pdu,
    )
    loop = asyncio.get_running_loop()
    stop = loop.create_future()

    def commands():
        for line in sys.stdin:
            parts = line.split()
            if not parts:
                continue
            cmd = parts[0]
            if cmd == "quit":
                break
            if cmd == "state":
                with drive.lock:
                    drive.advance()
                    state = {"event": "state", "rpm": drive.rpm, "target": drive.target, "fault": drive.fault}
                emit(state)
            elif cmd == "fault" and len(parts) == 2:
                with drive.lock:
                    drive.fault = int(parts[1])
                emit({"event": "ok", "command": cmd})
            elif cmd == "silent" and len(parts) == 2:
                with relay.lock:
                    relay.silent = parts[1] == "1"
                emit({"event": "ok", "command": cmd})
            elif cmd == "busy" and len(parts) == 2:
                with drive.lock:
                    busy["left"] = int(parts[1])
                emit({"event": "ok", "command": cmd})
            elif cmd == "corrupt" and len(parts) == 2:
                with relay.lock:
                    relay.corrupt = int(parts[1])
                emit({"event": "ok", "command": cmd})
            else:
                emit({"event": "error", "line": line.strip()})
        loop.call_soon_threadsafe(lambda: stop.done() or stop.set_result(None))

    threading.Thread(target=commands, daemon=True).start()
    serve = asyncio.create_task(server.serve_forever())
    await asyncio.sleep(0.2)
    emit({"event": "ready", "port": client_path})
    try:
        await asyncio.wait_for(stop, timeout=args.max_seconds)
    except asyncio.TimeoutError:
        emit({"event": "timeout"})
    await server.shutdown()
    serve.cancel()
    for fd in (client_master, client_slave, server_master, server_slave):
        os.close(fd)


if __name__ == "__main__":
    asyncio.run(main())
