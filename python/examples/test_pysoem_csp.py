"""pysoem brings a drivebus EtherCAT line to OP and runs a short cyclic
synchronous position (csp) sequence on an iPOS twin.

The fixture ``drivebus_ethercat`` (the drivebus pytest plugin) serves the
line in a network namespace on one end of a veth pair; the master opens
the other end. Needs root; elsewhere it is skipped with the reason. Run
it with ``pytest -rs python/examples/test_pysoem_csp.py`` (pysoem
installed).
"""

import time

import pytest

pysoem = pytest.importorskip("pysoem")

CSP = 8
SYNC0_NS = 4_000_000  # 4 ms: a multiple of the iPOS's 1 ms loop


def to_op(master):
    master.state = pysoem.OP_STATE
    master.send_processdata()
    master.receive_processdata(10_000)
    master.write_state()
    for _ in range(400):
        master.send_processdata()
        master.receive_processdata(10_000)
        if master.state_check(pysoem.OP_STATE, 5_000) == pysoem.OP_STATE:
            return
    raise AssertionError(f"not in OP: {[hex(s.state) for s in master.slaves]}")


@pytest.mark.drivebus(drives=["ipos"])
def test_op_and_csp(drivebus_ethercat):
    master = pysoem.Master()
    master.open(drivebus_ethercat.iface)
    try:
        assert master.config_init() == 1
        ipos = master.slaves[0]
        ipos.set_watchdog("processdata", 1000)
        ipos.sdo_write(0x6060, 0, bytes([CSP]))
        master.config_map()  # RxPDO1: 6040h, 607Ah; TxPDO1: 6041h, 6064h, ...
        assert master.config_dc()
        ipos.dc_sync(True, SYNC0_NS)
        assert master.state_check(pysoem.SAFEOP_STATE, 2_000_000) == pysoem.SAFEOP_STATE
        to_op(master)

        def cycle(controlword, target):
            ipos.output = controlword.to_bytes(2, "little") + target.to_bytes(4, "little", signed=True)
            master.send_processdata()
            ok = master.receive_processdata(100_000) == master.expected_wkc
            time.sleep(SYNC0_NS / 1e9)
            data = ipos.input
            return ok, int.from_bytes(data[0:2], "little"), int.from_bytes(data[2:6], "little", signed=True)

        start = int.from_bytes(ipos.sdo_read(0x6064, 0), "little", signed=True)
        for cw, want in ((0x06, 0x21), (0x07, 0x23), (0x0F, 0x27)):
            for _ in range(200):
                ok, sw, _ = cycle(cw, start)
                if ok and sw & 0x6F == want:
                    break
            else:
                raise AssertionError(f"controlword {cw:02X}h: statusword {sw:04X}h")
        assert ipos.sdo_read(0x6061, 0) == bytes([CSP])
        # A ramp of 100 targets, then hold the last one.
        target = start
        for k in range(1, 101):
            target = start + 50 * k
            cycle(0x0F, target)
        for _ in range(100):
            ok, sw, position = cycle(0x0F, target)
            if ok and abs(position - target) <= 10:
                break
        assert sw & 0x6F == 0x27, f"left operation enabled: {sw:04X}h"
        assert abs(position - target) <= 10, (position, target)
        print("csp: from", start, "to", position)
        master.state = pysoem.INIT_STATE
        master.write_state()
    finally:
        master.close()
