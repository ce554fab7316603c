"""drivebus: CANopen CiA 402 drive twins inside your Python process.

``VirtualBus(channel, drives)`` joins the in-process virtual CAN bus
``channel`` and hosts the drive twins ``drives`` (``"akd:1"``, the
``drivebus serve --drive`` syntax) on it in real time. With python-can
installed, the same is ``can.Bus(interface="drivebus", channel="virtual",
drives=["akd:1"])``; every bus of the process with the same channel shares
one virtual bus.

``Simulation(drives, bitrate)`` hosts the same twins on a virtual bus in
simulated time: ``advance(seconds)``, ``send``, and the frame log with
simulated timestamps, the same for the same calls.
"""

from ._drivebus import PROFILES, DriveState, Simulation, VirtualBus

__all__ = ["PROFILES", "DriveState", "Simulation", "VirtualBus"]
