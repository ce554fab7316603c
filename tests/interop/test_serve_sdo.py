"""canopen 2.4.1's SDO client, scanner and abort handling against the
virtual drives of `drivebus serve` over socketcand."""

from __future__ import annotations

import time

import canopen
import pytest
from canopen.sdo.exceptions import SdoAbortedError

from conftest import remote_node

NODE = 5
BLOB = bytes(range(256)) * 40  # 10 240 bytes, as in transport-feasibility.md §5


class FrameLog:
    """Records the data of every frame with one COB-ID seen by a Network."""

    def __init__(self, net: canopen.Network, cob_id: int):
        self.frames: list[bytes] = []
        net.subscribe(cob_id, self._on)

    def _on(self, can_id, data, timestamp):
        self.frames.append(bytes(data))


def eds_default(node: canopen.RemoteNode, index: int, sub: int = 0):
    obj = node.object_dictionary[index]
    if isinstance(obj, canopen.objectdictionary.ODVariable):
        return obj.default
    return obj[sub].default


def test_scan_finds_served_nodes(serve, networks):
    srv = serve("generic:5", "akd:1", "dds6:9")
    net = networks(*srv)
    net.scanner.search()
    deadline = time.monotonic() + 3.0
    while time.monotonic() < deadline and not {1, 5, 9} <= set(net.scanner.nodes):
        time.sleep(0.05)
    assert sorted(net.scanner.nodes) == [1, 5, 9]


def test_expedited_read_device_type_and_identity(node):
    resp = FrameLog(node.network, 0x580 + NODE)
    assert node.sdo[0x1000].raw == eds_default(node, 0x1000)
    # expedited upload response: scs=2, e=1 (byte 0 = 0x4x with bit 1 set)
    assert resp.frames and resp.frames[0][0] & 0xE2 == 0x42, resp.frames
    ident = node.sdo[0x1018]
    assert ident[0].raw >= 4
    for sub in (1, 2, 3):
        assert ident[sub].raw == eds_default(node, 0x1018, sub), f"1018h:{sub}"
    assert isinstance(ident[4].raw, int)


def test_expedited_write_and_read_back_heartbeat_time(node):
    node.sdo[0x1017].raw = 250
    assert node.sdo[0x1017].raw == 250
    node.sdo.download(0x1017, 0, (0).to_bytes(2, "little"))
    assert node.sdo.upload(0x1017, 0) == b"\x00\x00"


def test_segmented_read_device_name(node):
    resp = FrameLog(node.network, 0x580 + NODE)
    name = node.sdo[0x1008].raw
    assert name == eds_default(node, 0x1008)
    assert len(name) > 4
    # initiate upload response without the expedited bit: a segmented transfer
    assert resp.frames[0][0] & 0xE2 == 0x40, resp.frames[0].hex()
    assert len(resp.frames) >= 1 + (len(name) + 6) // 7
    # the raw bytes through the file-like API as well
    with node.sdo.open(0x1008, 0, "rb") as f:
        assert f.read() == name.encode()


def test_segmented_write_and_read_back_domain(node):
    payload = bytes(range(200))
    node.sdo.download(0x1F50, 1, payload, force_segment=True)
    assert node.sdo.upload(0x1F50, 1) == payload


@pytest.mark.limit(60)
def test_block_download_and_upload_with_crc(node):
    assert 0x1F50 in node.object_dictionary, "generic EDS lost 1F50h (program data, DOMAIN)"
    resp = FrameLog(node.network, 0x580 + NODE)
    with node.sdo.open(0x1F50, 1, "wb", size=len(BLOB), block_transfer=True, request_crc_support=True) as f:
        f.write(BLOB)
    # block download initiate response: scs=5 (0xA0), sc (bit 2) = server CRC support
    assert resp.frames[0][0] & 0xE3 == 0xA0, resp.frames[0].hex()
    assert resp.frames[0][0] & 0x04, "server did not announce CRC support in block download"

    resp.frames.clear()
    with node.sdo.open(0x1F50, 1, "rb", block_transfer=True, request_crc_support=True) as f:
        back = f.read()
    assert back == BLOB
    # block upload initiate response: scs=6 (0xC0), sc (bit 2) = CRC, s (bit 1) = size
    assert resp.frames[0][0] & 0xE3 == 0xC2, resp.frames[0].hex()
    assert resp.frames[0][0] & 0x04, "server did not announce CRC support in block upload"
    assert int.from_bytes(resp.frames[0][4:8], "little") == len(BLOB)


@pytest.mark.parametrize(
    "index, sub, write, code",
    [
        (0x2FFF, 0, None, 0x06020000),  # object does not exist
        (0x1018, 0x09, None, 0x06090011),  # sub-index does not exist
        (0x1000, 0, b"\x00\x00\x00\x00", 0x06010002),  # write to a read-only object
    ],
    ids=["no-object", "no-subindex", "read-only"],
)
def test_abort_codes_surface_as_sdo_aborted_error(node, index, sub, write, code):
    with pytest.raises(SdoAbortedError) as e:
        if write is None:
            node.sdo.upload(index, sub)
        else:
            node.sdo.download(index, sub, write)
    assert e.value.code == code, f"abort {e.value.code:08X}, expected {code:08X}"
    # the server is still fine afterwards
    assert node.sdo[0x1000].raw == eds_default(node, 0x1000)


def test_two_drives_answer_independently(serve, networks, eds_path):
    srv = serve("generic:5", "generic:6")
    net = networks(*srv)
    a, b = remote_node(net, 5, eds_path), remote_node(net, 6, eds_path)
    a.sdo[0x1017].raw = 111
    b.sdo[0x1017].raw = 222
    assert (a.sdo[0x1017].raw, b.sdo[0x1017].raw) == (111, 222)
