#!/usr/bin/env python3
"""CiA 402 servo drives emulated with the `canopen` package (LocalNode) on an slcan line.

An independent peer for klar's CANopen master: SDO server, NMT and heartbeat come from
`canopen`; the PDO handling and the CiA 402 power state machine are written here from the
CiA 301 / CiA 402 definitions. Each drive follows its CSP target exactly (a perfect servo),
so the master must read back exactly what it commanded. In cyclic synchronous velocity
(mode 9) it moves by exactly target velocity x interpolation period each SYNC (a perfect
velocity servo, fractions of a count carried over), so the position loop is the master's.

The peer checks the master while it runs and writes a JSON report at the end:
- PDO mappings may only change while the PDO is disabled and its count is 0 (else abort);
- receive PDOs and SYNC must have the lengths the mapping defines (SYNC: 0 bytes);
- every controlword must be a transition the current state allows, or keep the state;
- the CSP target must not move while the drive is not enabled, nor jump more than
  --max-step counts between SYNCs;
- the CSV target velocity must be 0 while the drive is not enabled, and must not move it
  more than --max-step counts in one SYNC;
- after the injected fault, the other drives must get a quick stop within 3 SYNCs.

It prints READY once listening, and ends when the master sends NMT stop to all nodes
(exit 0, or 1 if any rule was broken) or after --timeout seconds (exit 2).
"""

import argparse
import json
import struct
import sys
import threading
import time

import can
import canopen
from canopen import objectdictionary as od
from canopen.sdo.exceptions import SdoAbortedError

# CiA 402 power states and the statusword bits (0-3, 5, 6) that show them.
NOT_READY, SO_DISABLED, READY, SWITCHED_ON, OP_ENABLED, QUICK_STOP, FAULT_REACTION, FAULT = (
    "NOT_READY_TO_SWITCH_ON", "SWITCH_ON_DISABLED", "READY_TO_SWITCH_ON", "SWITCHED_ON",
    "OPERATION_ENABLED", "QUICK_STOP_ACTIVE", "FAULT_REACTION_ACTIVE", "FAULT")
STATE_BITS = {NOT_READY: 0x00, SO_DISABLED: 0x40, READY: 0x21, SWITCHED_ON: 0x23,
              OP_ENABLED: 0x27, QUICK_STOP: 0x07, FAULT_REACTION: 0x0F, FAULT: 0x08}


def command_of(cw):
    """Names the device control command in a controlword (bits 7, 3, 2, 1, 0)."""
    if cw & 0x0002 == 0:
        return "disable_voltage"
    if cw & 0x0006 == 0x0002:
        return "quick_stop"
    if cw & 0x0087 == 0x0006:
        return "shutdown"
    if cw & 0x008F == 0x0007:
        return "switch_on"
    if cw & 0x008F == 0x000F:
        return "enable_operation"
    return "other"


# (state, command) -> next state, from the CiA 402 state transition table.
TRANSITIONS = {
    (SO_DISABLED, "shutdown"): READY,
    (READY, "switch_on"): SWITCHED_ON,
    (READY, "enable_operation"): OP_ENABLED,
    (READY, "disable_voltage"): SO_DISABLED,
    (READY, "quick_stop"): SO_DISABLED,
    (SWITCHED_ON, "enable_operation"): OP_ENABLED,
    (SWITCHED_ON, "shutdown"): READY,
    (SWITCHED_ON, "disable_voltage"): SO_DISABLED,
    (SWITCHED_ON, "quick_stop"): SO_DISABLED,
    (OP_ENABLED, "switch_on"): SWITCHED_ON,
    (OP_ENABLED, "shutdown"): READY,
    (OP_ENABLED, "disable_voltage"): SO_DISABLED,
    (OP_ENABLED, "quick_stop"): QUICK_STOP,
    (QUICK_STOP, "disable_voltage"): SO_DISABLED,
}
# Commands that keep a state without being a transition.
HOLDS = {
    SO_DISABLED: {"disable_voltage", "quick_stop"},
    READY: {"shutdown"},
    SWITCHED_ON: {"switch_on"},
    OP_ENABLED: {"enable_operation"},
    QUICK_STOP: {"quick_stop"},
}


def build_dictionary():
    d = od.ObjectDictionary()

    def var(index, sub, name, dtype, access="rw", default=0, mappable=False):
        v = od.ODVariable(name, index, sub)
        v.data_type = dtype
        v.access_type = access
        v.default = default
        v.pdo_mappable = mappable
        return v

    def add(index, name, dtype, access="rw", default=0, mappable=False):
        d.add_object(var(index, 0, name, dtype, access, default, mappable))

    def record(index, name, members):
        r = od.ODRecord(name, index)
        for sub, (mname, dtype, access, default) in members.items():
            r.add_member(var(index, sub, mname, dtype, access, default))
        d.add_object(r)

    add(0x1000, "device type", od.UNSIGNED32, "ro", 0x00020192)
    add(0x1001, "error register", od.UNSIGNED8, "ro", 0, True)
    add(0x1008, "manufacturer device name", od.VISIBLE_STRING, "ro", DEVICE_NAME)
    add(0x1017, "producer heartbeat time", od.UNSIGNED16, "rw", 0)
    add(0x2000, "scratch domain", od.DOMAIN, "rw", b"")
    for p in range(4):
        for comm, mapping, base in ((0x1400 + p, 0x1600 + p, 0x200), (0x1800 + p, 0x1A00 + p, 0x180)):
            cob = base + 0x100 * p  # node ID added per node below
            record(comm, "pdo comm %d" % p, {
                0: ("count", od.UNSIGNED8, "ro", 2),
                1: ("cob id", od.UNSIGNED32, "rw", cob),
                2: ("transmission type", od.UNSIGNED8, "rw", 0xFF),
            })
            members = {0: ("count", od.UNSIGNED8, "rw", 0)}
            for s in range(1, 9):
                members[s] = ("entry %d" % s, od.UNSIGNED32, "rw", 0)
            record(mapping, "pdo mapping %d" % p, members)
    add(0x603F, "error code", od.UNSIGNED16, "ro", 0, True)
    add(0x6040, "controlword", od.UNSIGNED16, "rw", 0, True)
    add(0x6041, "statusword", od.UNSIGNED16, "ro", 0, True)
    add(0x6060, "modes of operation", od.INTEGER8, "rw", 0, True)
    add(0x6061, "modes of operation display", od.INTEGER8, "ro", 0, True)
    add(0x6064, "position actual value", od.INTEGER32, "ro", 0, True)
    add(0x6065, "following error window", od.UNSIGNED32, "rw", 0xFFFFFFFF)
    add(0x607A, "target position", od.INTEGER32, "rw", 0, True)
    add(0x607C, "home offset", od.INTEGER32, "rw", 0)
    add(0x60FF, "target velocity", od.INTEGER32, "rw", 0, True)
    add(0x6098, "homing method", od.INTEGER8, "rw", 0)
    record(0x6099, "homing speeds", {
        0: ("count", od.UNSIGNED8, "ro", 2),
        1: ("search for switch", od.UNSIGNED32, "rw", 0),
        2: ("search for zero", od.UNSIGNED32, "rw", 0),
    })
    add(0x609A, "homing acceleration", od.UNSIGNED32, "rw", 0)
    record(0x60C2, "interpolation time period", {
        0: ("count", od.UNSIGNED8, "ro", 2),
        1: ("value", od.UNSIGNED8, "rw", 1),
        2: ("index", od.INTEGER8, "rw", -3),
    })
    return d


FORMATS = {8: "<B", 16: "<H", 32: "<I"}
DEVICE_NAME = "canopen peer CiA 402 drive"

SIGNED = {0x6060, 0x6061, 0x6064, 0x607A, 0x607C, 0x6098, 0x60FF}


class Drive:
    def __init__(self, peer, node_id):
        self.peer = peer
        self.id = node_id
        self.node = canopen.LocalNode(node_id, build_dictionary())
        self.node.add_write_callback(self.on_sdo_write)
        self.node.add_read_callback(self.on_sdo_read)
        self.state = SO_DISABLED
        self.last_cw = 0
        self.position = 0
        self.fraction = 0.0
        self.last_target = None
        self.syncs_enabled = 0
        self.homed = False
        self.report = {"states": [SO_DISABLED], "boot_ups": 0, "nmt": [], "syncs": 0,
                       "quick_stop_at_sync": None, "fault_resets": 0, "homed": False,
                       "csv_syncs": 0}

    def violation(self, text):
        self.peer.violation("node %d: %s" % (self.id, text))

    def u(self, index, sub):
        """An unsigned value from the data store (or the dictionary default)."""
        raw = self.node.get_data(index, sub)
        return int.from_bytes(raw, "little")

    def s(self, index, sub=0):
        raw = self.node.get_data(index, sub)
        return int.from_bytes(raw, "little", signed=True)

    def put(self, index, value, sub=0):
        obj = self.node._find_object(index, sub)
        bits = len(obj)
        mask = (1 << bits) - 1
        self.node.data_store.setdefault(index, {})[sub] = struct.pack(FORMATS[bits], value & mask)

    def cob(self, comm):
        value = self.u(comm, 1)
        # Default COB-IDs in the dictionary lack the node ID; add it if untouched.
        if comm not in self.node.data_store or 1 not in self.node.data_store[comm]:
            value += self.id
        return value

    def period(self):
        """The interpolation period (0x60C2) in seconds."""
        return self.u(0x60C2, 1) * 10.0 ** self.s(0x60C2, 2)

    def on_sdo_read(self, index, subindex, od):
        """The mode display follows the mode of operation at once."""
        if index == 0x6061:
            return self.s(0x6060)
        return None

    def on_sdo_write(self, index, subindex, od, data):
        """Enforces CiA 301's PDO mapping procedure on SDO writes."""
        if 0x1600 <= index <= 0x1603 or 0x1A00 <= index <= 0x1A03:
            if self.cob(index - 0x200) & 0x80000000 == 0:
                self.violation("mapping 0x%04X:%d written while the PDO is valid" % (index, subindex))
                raise SdoAbortedError(0x08000022)
            if subindex != 0 and self.u(index, 0) != 0:
                self.violation("mapping 0x%04X:%d written while its count is not 0" % (index, subindex))
                raise SdoAbortedError(0x08000022)
            if subindex == 0:
                count = data[0]
                total = 0
                for s in range(1, count + 1):
                    total += self.u(index, s) & 0xFF
                if total > 64:
                    raise SdoAbortedError(0x06040042)

    def mapping(self, comm, mapping):
        cob = self.cob(comm)
        if cob & 0x80000000:
            return None
        entries = []
        for s in range(1, self.u(mapping, 0) + 1):
            v = self.u(mapping, s)
            entries.append((v >> 16, (v >> 8) & 0xFF, v & 0xFF))
        return cob & 0x7FF, entries

    def on_nmt(self, can_id, data, timestamp):
        if len(data) != 2:
            self.violation("NMT command with %d bytes" % len(data))
            return
        cmd, target = data[0], data[1]
        if target not in (0, self.id):
            return
        self.report["nmt"].append(cmd)
        if cmd in (0x81, 0x82):
            if cmd == 0x81:
                self.node.data_store.clear()
            else:
                for index in [i for i in self.node.data_store if 0x1000 <= i <= 0x1FFF]:
                    del self.node.data_store[index]
            self.boot()
        elif cmd == 0x02 and target == 0:
            self.peer.stop_requested.set()

    def boot(self):
        self.node.nmt.send_command(0x82)  # to INITIALISING: sends the boot-up message
        self.node.nmt.send_command(0x80)  # to PRE-OPERATIONAL: starts the heartbeat
        self.report["boot_ups"] += 1

    def operational(self):
        return self.node.nmt.state == "OPERATIONAL"

    def on_rpdo(self, can_id, data, timestamp):
        if not self.operational():
            return
        for p in range(4):
            m = self.mapping(0x1400 + p, 0x1600 + p)
            if m is None or m[0] != can_id:
                continue
            entries = m[1]
            need = sum(bits // 8 for _, _, bits in entries)
            if len(data) != need:
                self.violation("RPDO 0x%03X with %d bytes, mapping needs %d" % (can_id, len(data), need))
                return
            at = 0
            for index, sub, bits in entries:
                n = bits // 8
                self.node.data_store.setdefault(index, {})[sub] = bytes(data[at:at + n])
                at += n

    def set_state(self, state):
        if state != self.state:
            self.state = state
            self.report["states"].append(state)

    def on_sync(self):
        if not self.operational():
            return
        self.report["syncs"] += 1
        cw = self.u(0x6040, 0)
        target = self.s(0x607A)
        mode = self.s(0x6060)
        reset_edge = cw & 0x80 and not self.last_cw & 0x80
        start_edge = cw & 0x10 and not self.last_cw & 0x10
        self.last_cw = cw
        cmd = command_of(cw)
        if self.state == FAULT:
            if reset_edge:
                self.report["fault_resets"] += 1
                self.set_state(SO_DISABLED)
                self.node.emcy.reset()
        elif (self.state, cmd) in TRANSITIONS:
            nxt = TRANSITIONS[(self.state, cmd)]
            if nxt == QUICK_STOP and self.report["quick_stop_at_sync"] is None:
                self.report["quick_stop_at_sync"] = self.peer.sync_count
            self.set_state(nxt)
        elif cmd not in HOLDS.get(self.state, set()):
            self.violation("controlword 0x%04X (%s) in %s" % (cw, cmd, self.state))
        enabled = self.state == OP_ENABLED
        if enabled and mode == 8:
            if self.last_target is not None and abs(target - self.last_target) > self.peer.max_step:
                self.violation("CSP target jumped %d counts" % (target - self.last_target))
            self.position = target
        elif enabled and mode == 6 and start_edge:
            if self.s(0x6098) in (35, 37):
                self.position = self.s(0x607C)
                self.homed = True
                self.report["homed"] = True
            else:
                self.violation("homing method %d not emulated" % self.s(0x6098))
        elif enabled and mode == 9:
            exact = self.s(0x60FF) * self.period() + self.fraction
            step = int(round(exact))
            self.fraction = exact - step
            if abs(step) > self.peer.max_step:
                self.violation("CSV target velocity %d moves %d counts in one SYNC" % (self.s(0x60FF), step))
            self.position += step
            self.report["csv_syncs"] += 1
        elif not enabled and mode == 9 and self.s(0x60FF) != 0 and self.state != FAULT:
            self.violation("target velocity %d while %s" % (self.s(0x60FF), self.state))
        elif not enabled and mode != 9 and target != self.position and self.state != FAULT:
            self.violation("target %d differs from position %d while %s" % (target, self.position, self.state))
        # The next CSP step is measured from the target if following, else from the
        # position (after homing or re-enabling, the drive starts where it stands).
        self.last_target = target if enabled and mode == 8 else self.position
        if enabled:
            self.syncs_enabled += 1
        sw = STATE_BITS[self.state] | 0x0200
        if self.state in (SWITCHED_ON, OP_ENABLED, QUICK_STOP):
            sw |= 0x0010
        if enabled and mode == 8:
            sw |= 0x1000 | 0x0400
        if enabled and mode == 9:
            sw |= 0x1000
        if enabled and mode == 6 and self.homed:
            sw |= 0x1000 | 0x0400
        self.put(0x6041, sw)
        self.put(0x6064, self.position)
        self.put(0x6061, mode)
        self.transmit()

    def transmit(self):
        for p in range(4):
            m = self.mapping(0x1800 + p, 0x1A00 + p)
            if m is None:
                continue
            if not 1 <= self.u(0x1800 + p, 2) <= 240:
                continue
            payload = b"".join(self.node.get_data(i, s)[: bits // 8] for i, s, bits in m[1])
            self.peer.network.send_message(m[0], payload)

    def fault(self, code):
        self.put(0x603F, code)
        self.put(0x1001, 0x01)
        self.node.emcy.send(code, 0x01)
        self.set_state(FAULT)


class Peer:
    def __init__(self, args):
        self.args = args
        self.max_step = args.max_step
        self.violations = []
        self.lock = threading.Lock()
        self.stop_requested = threading.Event()
        self.sync_count = 0
        self.fault_at_sync = None
        self.bus = can.Bus(interface="slcan", channel=args.port, bitrate=args.bitrate,
                           sleep_after_open=0)
        self.network = canopen.Network(self.bus)
        self.drives = [Drive(self, n) for n in args.nodes]
        for d in self.drives:
            self.network.add_node(d.node)
            self.network.subscribe(0, d.on_nmt)
        self.network.subscribe(0x80, self.on_sync)
        # PDO COB-IDs may be changed by the master: listen on the whole PDO range.
        for cob in range(0x180, 0x580):
            self.network.subscribe(cob, self.on_pdo)
        self.network.connect()

    def violation(self, text):
        if text not in self.violations:
            self.violations.append(text)
            print("VIOLATION " + text, file=sys.stderr, flush=True)

    def on_pdo(self, can_id, data, timestamp):
        with self.lock:
            for d in self.drives:
                d.on_rpdo(can_id, data, timestamp)

    def on_sync(self, can_id, data, timestamp):
        with self.lock:
            if len(data) != 0:
                self.violation("SYNC with %d data bytes" % len(data))
            self.sync_count += 1
            for d in self.drives:
                d.on_sync()
            self.inject()
            self.check_reaction()

    def inject(self):
        a = self.args
        if a.fault_node is None or self.fault_at_sync is not None:
            return
        for d in self.drives:
            if d.id == a.fault_node and d.syncs_enabled >= a.fault_after:
                d.fault(a.fault_code)
                self.fault_at_sync = self.sync_count

    def check_reaction(self):
        if self.fault_at_sync is None:
            return
        for d in self.drives:
            if d.id == self.args.fault_node:
                continue
            qs = d.report["quick_stop_at_sync"]
            late = self.sync_count - self.fault_at_sync > 3
            if late and (qs is None or qs < self.fault_at_sync):
                self.violation("node %d: no quick stop within 3 SYNCs of the fault" % d.id)

    def run(self):
        for d in self.drives:
            d.boot()
        print("READY", flush=True)
        finished = self.stop_requested.wait(self.args.timeout)
        time.sleep(0.05)
        with self.lock:
            if not finished:
                self.violation("timeout: no NMT stop within %.0f s" % self.args.timeout)
            report = {
                "violations": self.violations,
                "syncs": self.sync_count,
                "fault_at_sync": self.fault_at_sync,
                "nodes": {},
            }
            for d in self.drives:
                r = dict(d.report)
                r["position"] = d.position
                r["heartbeat_ms"] = d.u(0x1017, 0)
                r["interpolation"] = [d.u(0x60C2, 1), d.s(0x60C2, 2)]
                r["homing_method"] = d.s(0x6098)
                pdos = {}
                for name, comm, mapping in (("rpdo", 0x1400, 0x1600), ("tpdo", 0x1800, 0x1A00)):
                    for p in range(4):
                        m = d.mapping(comm + p, mapping + p)
                        if m is not None:
                            pdos["%s%d" % (name, p + 1)] = {
                                "cob_id": m[0],
                                "transmission": d.u(comm + p, 2),
                                "entries": [(i << 16) | (s << 8) | b for i, s, b in m[1]],
                            }
                r["pdos"] = pdos
                report["nodes"][str(d.id)] = r
        with open(self.args.report, "w") as f:
            json.dump(report, f, indent=1)
        self.network.disconnect()
        if not finished:
            return 2
        return 1 if self.violations else 0


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--port", required=True, help="serial device of the slcan line")
    ap.add_argument("--bitrate", type=int, default=1000000)
    ap.add_argument("--nodes", type=int, nargs="+", default=[1])
    ap.add_argument("--report", required=True, help="where to write the JSON report")
    ap.add_argument("--timeout", type=float, default=60.0)
    ap.add_argument("--max-step", type=int, default=1000, help="largest CSP target step, counts")
    ap.add_argument("--fault-node", type=int, default=None)
    ap.add_argument("--fault-after", type=int, default=100, help="SYNCs in operation enabled")
    ap.add_argument("--fault-code", type=lambda s: int(s, 0), default=0x2310)
    args = ap.parse_args()
    sys.exit(Peer(args).run())


if __name__ == "__main__":
    main()
