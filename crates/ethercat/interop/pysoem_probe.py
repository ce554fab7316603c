"""SOEM (through pysoem) against drivebus digital I/O slaves.

Usage: python pysoem_probe.py IFNAME SLAVES CYCLES MASK[,MASK...]

Discovers the slaves, checks names and the SII identity, maps process data
(SOEM reads the PDOs from the SII categories), goes to OP, runs CYCLES
cycles of 1 ms with the expected working counter and checks that every
slave's inputs equal its previous outputs XOR its mask. Prints one summary
line; exit status 0 on success.
"""
import sys
import time

import pysoem

VENDOR_ID = 0x0DB0


def main():
    ifname, slaves, cycles = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
    masks = [int(m, 0) for m in sys.argv[4].split(",")]
    master = pysoem.Master()
    master.open(ifname)
    try:
        found = master.config_init()
        if found != slaves:
            print(f"error: found {found} slaves, expected {slaves}")
            return 1
        master.config_map()
        for i, s in enumerate(master.slaves):
            print(f"slave {i} {s.name} vendor {s.man:#010x} product {s.id:#010x} "
                  f"in {len(s.input)} B out {len(s.output)} B")
            if s.man != VENDOR_ID or not s.name.startswith("DB-DIO"):
                print("error: identity")
                return 1
        if master.state_check(pysoem.SAFEOP_STATE, 500_000) != pysoem.SAFEOP_STATE:
            print(f"error: not all in SAFE-OP ({[hex(s.state) for s in master.slaves]})")
            return 1
        expected = master.expected_wkc
        master.state = pysoem.OP_STATE
        master.send_processdata()
        master.receive_processdata(10_000)
        master.write_state()
        for _ in range(200):
            master.send_processdata()
            master.receive_processdata(10_000)
            if master.state_check(pysoem.OP_STATE, 5_000) == pysoem.OP_STATE:
                break
        else:
            print(f"error: not all in OP ({[hex(s.state) for s in master.slaves]})")
            return 1
        history = []
        bad_wkc = bad_data = late = 0
        for k in range(cycles):
            outs = []
            for i, s in enumerate(master.slaves):
                n = len(s.output)
                v = (k * 0x9E3779B9 + i * 0x1234567) & ((1 << (8 * n)) - 1)
                s.output = v.to_bytes(n, "little")
                outs.append(v)
            history.append(outs)
            master.send_processdata()
            wkc = master.receive_processdata(10_000)
            if wkc != expected:
                bad_wkc += 1
            if k >= 2:
                for i, s in enumerate(master.slaves):
                    n = len(s.input)
                    m = masks[i] & ((1 << (8 * n)) - 1)
                    got = int.from_bytes(s.input, "little")
                    if got == history[k - 1][i] ^ m:
                        pass
                    elif got == history[k - 2][i] ^ m:
                        late += 1
                    else:
                        bad_data += 1
            time.sleep(0.001)
        master.state = pysoem.INIT_STATE
        master.write_state()
        print(f"slaves={found} cycles={cycles} expected_wkc={expected} bad_wkc={bad_wkc} "
              f"bad_data={bad_data} late_data={late}")
        return 0 if bad_wkc == 0 and bad_data == 0 else 1
    finally:
        master.close()


if __name__ == "__main__":
    sys.exit(main())
