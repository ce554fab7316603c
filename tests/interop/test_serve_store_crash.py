"""Crash safety of 1010h "save all parameters" (issue 11 §6).

`drivebus serve --state-dir` is killed with SIGKILL at random moments
around a 1010h:01 save, over and over. Every restart must come up and find
either the complete old parameter set or the complete new one: never one
group from before the save and another from after it, never garbage. A
save the drive confirmed before the kill must be found.
"""

from __future__ import annotations

import random
import threading
import time

import can
import pytest

from conftest import LOCALHOST, connect, free_port, remote_node, start_serve

NODE = 5
ROUNDS = 100
SAVE = 0x65766173  # "save", CiA 301 §7.5.2.13
# One object per stored group: 1017h is a communication parameter, 6083h
# and 6084h application parameters (they are stored in separate images).
OBJECTS = (0x1017, 0x6083, 0x6084)


def values_for(k: int) -> dict[int, int]:
    return {0x1017: 100 + k, 0x6083: 10_000 + k, 0x6084: 20_000 + k}


@pytest.mark.limit(600)
def test_sigkill_during_save_leaves_old_or_new_set(eds_path, tmp_path):
    rng = random.Random(0x1010)
    state = tmp_path / "state"
    persisted: dict[int, int] | None = None  # the set the last restart found
    attempt: tuple[dict[int, int], bool] | None = None  # (set sent for saving, confirmed)
    outcomes = {"old": 0, "new": 0}

    def check_restart(k: int, found: dict[int, int]) -> None:
        nonlocal persisted
        if attempt is not None:
            new, confirmed = attempt
            if found == new:
                outcomes["new"] += 1
            else:
                assert not confirmed, f"round {k}: a save confirmed before the kill is lost: {found}, not {new}"
                assert found == persisted, f"round {k}: neither the old set {persisted} nor the new {new}: {found}"
                outcomes["old"] += 1
        persisted = found

    for k in range(1, ROUNDS + 1):
        served = start_serve(f"generic:{NODE}", state_dir=state, port=free_port())
        net = connect(LOCALHOST, served.port)
        try:
            node = remote_node(net, NODE, eds_path)
            check_restart(k, {i: node.sdo[i].raw for i in OBJECTS})
            new = values_for(k)
            for i, v in new.items():
                node.sdo[i].raw = v
            answered = threading.Event()

            def on_response(can_id, data, timestamp):
                if data[:4] == bytes([0x60, 0x10, 0x10, 0x01]):
                    answered.set()

            net.subscribe(0x580 + NODE, on_response)
            net.send_message(0x600 + NODE, bytes([0x23, 0x10, 0x10, 0x01]) + SAVE.to_bytes(4, "little"))
            # Most kills land while the save is in flight; some before it
            # reached the drive, some after it finished.
            time.sleep(rng.choice((0.0, rng.uniform(0, 0.004), rng.uniform(0, 0.004), rng.uniform(0, 0.02))))
            served.proc.p.kill()
            served.proc.p.wait(timeout=10)
            served.proc.returncode = served.proc.p.returncode
            attempt = (new, answered.is_set())
        finally:
            try:
                net.disconnect()
            except (OSError, can.CanError):
                # The server was killed under the connection: a reset is
                # expected (python-can wraps it in a CanError).
                pass
            if served.proc.p.poll() is None:
                served.proc.p.kill()
                served.proc.p.wait(timeout=10)

    # The last restart must come up too, with a consistent set.
    served = start_serve(f"generic:{NODE}", state_dir=state, port=free_port())
    net = connect(LOCALHOST, served.port)
    try:
        node = remote_node(net, NODE, eds_path)
        check_restart(ROUNDS + 1, {i: node.sdo[i].raw for i in OBJECTS})
    finally:
        net.disconnect()
        served.stop()
    print(f"SIGKILL rounds: {ROUNDS}; restarts found the new set {outcomes['new']} times, the old {outcomes['old']}")
    # Both outcomes must have happened, or the kills never hit the save window.
    assert outcomes["new"] > 0 and outcomes["old"] > 0, outcomes
