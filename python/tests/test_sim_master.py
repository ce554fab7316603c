"""The simulated-time master beyond SDO and NMT: PDO configuration
(`master.pdo`, as `drivebus pdo`), LSS (`master.lss`), SYNC and a CSP
stream (`drive(n).csp`), the frame log as columns (`sim.frame_log`) and
an object plotted over simulated time (`drivebus.plot`)."""

from __future__ import annotations

import sys

import pytest

import drivebus


def _akd():
    sim = drivebus.Simulation(drives=["akd:1"])
    return sim, sim.master()


def test_pdo_show_lists_the_rpdos_then_the_tpdos():
    _, m = _akd()
    pdos = m.pdo.show(1)
    dirs = [p["dir"] for p in pdos]
    assert dirs == sorted(dirs)  # RPDO before TPDO
    assert {"RPDO", "TPDO"} <= set(dirs)
    first = [p for p in pdos if p["dir"] == "TPDO"][0]
    assert first["number"] == 1 and first["cob_id"] == 0x181
    assert first == m.pdo.read(1, "tpdo", 1)


def test_pdo_map_then_the_tpdo_comes_on_sync():
    sim, m = _akd()
    m.pdo.map(1, "tpdo", 1, ["statusword", "6064:0:32"], transmission=1)
    got = m.pdo.read(1, "tpdo", 1)
    assert [(e["index"], e["sub"], e["bits"]) for e in got["mapping"]] == [(0x6041, 0, 16), (0x6064, 0, 32)]
    assert got["mapping"][0]["name"].lower() == "statusword"
    assert got["transmission_type"] == 1 and got["valid"]
    m.nmt(1, "start")
    m.start_sync(0.001)
    t0 = sim.now
    sim.advance(0.01)
    m.stop_sync()
    tpdos = [data for (t, cob, _, _, _, data) in sim.log() if t >= t0 and cob == 0x181]
    assert len(tpdos) >= 9 and all(len(d) == 6 for d in tpdos)
    sw = int.from_bytes(tpdos[-1][:2], "little")
    assert sw == m.sdo_read(1, 0x6041)


def test_a_refused_mapping_names_the_cause_and_restores_the_previous_one():
    _, m = _akd()
    before = m.pdo.read(1, "tpdo", 1)
    # 1000h cannot be mapped: the drive refuses the entry.
    with pytest.raises(drivebus.SdoError, match=r"^node 1: TPDO1 mapping refused; the previous mapping of TPDO1 is in force again: node 1: SDO write 1A00h:01"):
        m.pdo.map(1, "tpdo", 1, [(0x1000, 0, 32)])
    assert m.pdo.read(1, "tpdo", 1) == before
    with pytest.raises(ValueError, match="bad PDO direction"):
        m.pdo.read(1, "up", 1)
    with pytest.raises(ValueError, match="BITS must be 1..64"):
        m.pdo.map(1, "tpdo", 1, ["6041:0:99"])


def test_lss_inquires_and_configures_the_node_id():
    # generic has LSS (CiA 305); the AKD's manual does not mention it.
    sim = drivebus.Simulation(drives=["generic:1"])
    m = sim.master()
    vendor = m.sdo_read(1, 0x1018, 1)
    lss = m.lss
    lss.switch_global("configuration")
    assert lss.inquire_node_id() == 1
    assert lss.inquire_identity()["vendor_id"] == vendor
    lss.configure_node_id(5)
    lss.switch_global("waiting")
    m.nmt(0, "reset-comm")
    sim.advance(0.1)
    assert m.sdo_read(5, 0x1018, 1) == vendor
    with pytest.raises(drivebus.SdoError, match="timed out"):
        m.sdo_read(1, 0x1000)
    with pytest.raises(ValueError, match="bad LSS mode"):
        lss.switch_global("on")
    with pytest.raises(ValueError, match="not in 1..127"):
        lss.configure_node_id(0)
    # No slave in configuration: nobody answers.
    with pytest.raises(drivebus.DrivebusError, match="LSS: no answer"):
        lss.inquire_node_id()


def test_lss_finds_no_slave_on_a_drive_without_it():
    _, m = _akd()
    m.lss.switch_global("configuration")
    with pytest.raises(drivebus.DrivebusError, match="LSS: no answer"):
        m.lss.inquire_node_id()


def test_csp_stream_follows_one_target_per_sync():
    sim, m = _akd()
    d = m.drive(1)
    with pytest.raises(drivebus.DriveError, match="SYNC"):
        d.csp([0])
    m.nmt(1, "start")
    m.start_sync(0.001)
    d.enable()
    p0 = d.position
    t0 = sim.now
    targets = [p0 + 20 * k for k in range(1, 201)]
    assert d.csp(targets) == 200
    syncs = [t for (t, cob, _, _, _, _) in sim.log() if t >= t0 and cob == 0x80]
    assert len(syncs) >= 200
    assert m.sdo_read(1, 0x6061) == 8
    sim.advance(0.1)
    assert abs(d.position - targets[-1]) <= 20
    assert d.state == "operation enabled"


def test_frame_log_columns_rows_and_numpy_agree():
    sim, m = _akd()
    m.sdo_read(1, 0x1000)
    log = sim.log()
    cols = sim.frame_log()
    assert list(cols) == ["time", "id", "extended", "remote", "dlc", "data"]
    assert all(len(v) == len(log) for v in cols.values())
    assert list(zip(*cols.values())) == log
    rows = sim.frame_log(columns=False)
    assert [tuple(r.values()) for r in rows] == log
    np = pytest.importorskip("numpy")
    arr = sim.frame_log(numpy=True)
    assert arr.dtype.names == ("time", "id", "extended", "remote", "dlc", "data")
    assert arr["id"].tolist() == cols["id"]
    assert np.allclose(arr["time"], cols["time"])
    sdo = [i for i, r in enumerate(log) if r[1] == 0x581][0]
    assert bytes(arr["data"][sdo][: arr["dlc"][sdo]]) == log[sdo][5]


def test_frame_log_numpy_without_numpy_names_the_package(monkeypatch):
    sim, _ = _akd()
    sim.advance(0.01)
    monkeypatch.setitem(sys.modules, "numpy", None)
    with pytest.raises(ImportError, match=r"frame_log\(numpy=True\) needs numpy"):
        sim.frame_log(numpy=True)
    assert sim.frame_log()["id"]  # the columns need nothing


def test_sample_reads_an_object_every_period_of_simulated_time():
    sim, m = _akd()
    t0 = sim.now
    times, values = m.sample(1, "statusword", seconds=0.1, period=0.01)
    assert len(times) == len(values) == 10
    assert times[0] == pytest.approx(t0, abs=1e-3)
    assert [round(b - a, 4) for a, b in zip(times, times[1:])] == [0.01] * 9
    assert set(values) == {m.sdo_read(1, 0x6041)}
    with pytest.raises(ValueError, match="period must be above 0"):
        m.sample(1, 0x6041, seconds=1, period=0)


def test_plot_draws_an_object_over_simulated_time():
    pytest.importorskip("matplotlib")
    import matplotlib

    matplotlib.use("Agg")
    sim, m = _akd()
    ax = drivebus.plot(sim, 1, "statusword", seconds=0.05, period=0.01)
    (line,) = ax.get_lines()
    assert len(line.get_xdata()) == 5
    assert ax.get_xlabel() == "simulated time (s)"
    assert line.get_label() == "node 1 statusword"


def test_plot_without_matplotlib_names_the_package(monkeypatch):
    monkeypatch.setitem(sys.modules, "matplotlib", None)
    monkeypatch.setitem(sys.modules, "matplotlib.pyplot", None)
    sim, _ = _akd()
    with pytest.raises(ImportError, match="drivebus.plot needs matplotlib .*pip install matplotlib"):
        drivebus.plot(sim, 1, 0x6041)
