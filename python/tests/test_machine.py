"""Drives on a machine file, as `drivebus serve --machine FILE` hosts them."""

from __future__ import annotations

import can
import pytest

import drivebus


def test_machine_file_sets_the_start_position(channel, tmp_path):
    f = tmp_path / "machine.toml"
    f.write_text("[[node]]\nid = 1\nstart = 90\n")
    with can.Bus(interface="drivebus", channel=channel, drives=["akd:1", "dds6:2"], machine=f) as bus:
        on_file, default = bus.drives
    with can.Bus(interface="drivebus", channel=channel + "-default", drives=["akd:1"]) as bus:
        (plain,) = bus.drives
    assert on_file.position != plain.position
    assert default.node == 2  # no table: the profile's default machine
    sim = drivebus.Simulation(drives=["akd:1"], machine=str(f))
    assert sim.drives[0].position == on_file.position


def test_bad_machine_files_raise_the_cli_message(channel, tmp_path):
    missing = tmp_path / "nope.toml"
    with pytest.raises(ValueError, match=str(missing)):
        drivebus.VirtualBus(channel, ["akd:1"], missing)
    f = tmp_path / "machine.toml"
    f.write_text("[[node]]\nid = 3\nstart = 90\n")  # node 3 is not hosted
    with pytest.raises(ValueError, match=rf"{f}: .*3"):
        drivebus.VirtualBus(channel, ["akd:1"], f)
    f.write_text("[[node]]\nid = 1\nstart = \n")
    with pytest.raises(ValueError, match=rf"{f}:"):
        drivebus.Simulation(["akd:1"], machine=f)
