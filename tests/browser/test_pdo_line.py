"""The PDO mapping editor and the EtherCAT line view in headless Chromium.

Against `serve --drive akd:1 --drive dds6:2`: an object picked in the
dictionary browser is added to TPDO2 and applied; the editor shows the
mapping the drive reads back, and the API agrees. Against `ethercat serve
--drive ipos --drive generic` on a veth pair (root): the line view lists
both slaves in order with their ESM state and AL status.
"""

import json
import os
import re
import subprocess
import urllib.request

import pytest
from selenium.webdriver.common.by import By
from selenium.webdriver.support.ui import Select

from test_page import BIN, browser, serve_page, shot, text, wait_for  # noqa: F401 (browser is a fixture)


@pytest.fixture(scope="module")
def serve_url():
    yield from serve_page("--drive", "akd:1", "--drive", "dds6:2")


def api_get(url, path):
    with urllib.request.urlopen(url.rstrip("/") + path, timeout=30) as r:
        return json.load(r)


def tpdo2_rows(b):
    return b.find_elements(By.CSS_SELECTOR, '#pdo-list .pdo[data-dir="tx"][data-num="2"] tbody tr')


def tpdo2_button(b, label):
    return next(
        x for x in b.find_elements(By.CSS_SELECTOR, '#pdo-list .pdo[data-dir="tx"][data-num="2"] button') if x.text == label
    )


def test_map_an_object_from_the_dictionary_into_a_tpdo(browser, serve_url):
    browser.get(serve_url)
    wait_for(browser, "node 1 in the PDO editor", lambda b: Select(b.find_element(By.ID, "pdo-node")).options)
    Select(browser.find_element(By.ID, "pdo-node")).select_by_value("1")
    wait_for(browser, "TPDO2 listed", lambda b: b.find_elements(By.CSS_SELECTOR, '#pdo-list .pdo[data-dir="tx"][data-num="2"]'))
    # Empty TPDO2 first, so what is read back is only what the page mapped.
    for _ in range(len(tpdo2_rows(browser))):
        tpdo2_rows(browser)[0].find_elements(By.TAG_NAME, "button")[-1].click()
    # Pick 606Ch (velocity actual value) in the dictionary browser of node 1.
    Select(browser.find_element(By.ID, "sdo-node")).select_by_value("1")
    q = browser.find_element(By.ID, "od-q")
    q.clear()
    q.send_keys("606C")
    browser.find_element(By.CSS_SELECTOR, '#od-search button[type="submit"]').click()
    row = wait_for(
        browser, "606Ch in the dictionary", lambda b: b.find_elements(By.CSS_SELECTOR, '#od tbody tr[data-index="606C"]')
    )[0]
    row.click()
    tpdo2_button(browser, "add").click()
    tpdo2_button(browser, "apply").click()
    wait_for(browser, "TPDO2 written", lambda b: "TPDO2 written" in text(b, "pdo-out"))
    rows = wait_for(browser, "TPDO2's mapping read back", lambda b: (r := tpdo2_rows(b)) and len(r) == 1 and r)
    assert rows[0].get_attribute("data-index") == "606C"
    assert "32 bits" in rows[0].text, rows[0].text
    shot(browser, "web-pdo.png")
    # The drive has it: the API reads TPDO2 back from the drive.
    pdo = api_get(serve_url, "/api/nodes/1/pdo")
    assert [(m["index"], m["bits"]) for m in pdo["tpdo"][1]["mapping"]] == [("606C", 32)], pdo


@pytest.fixture(scope="module")
def line_url():
    """`ethercat serve` on one end of a veth pair (needs root), with --http."""
    if os.geteuid() != 0:
        pytest.skip("ethercat serve needs root for a veth pair and AF_PACKET")
    a, b = f"dbbr{os.getpid() % 10000}a", f"dbbr{os.getpid() % 10000}b"
    made = subprocess.run(["ip", "link", "add", a, "type", "veth", "peer", "name", b], capture_output=True, text=True)
    if made.returncode != 0:
        pytest.skip(f"cannot create a veth pair: {made.stderr.strip()}")
    proc = None
    try:
        for end in (a, b):
            subprocess.run(["ip", "link", "set", end, "up"], check=True)
        proc = subprocess.Popen(
            [BIN, "ethercat", "serve", "--iface", a, "--drive", "ipos", "--drive", "generic", "--http", "127.0.0.1:0"],
            stdout=subprocess.PIPE,
            stderr=subprocess.STDOUT,
            text=True,
        )
        line = proc.stdout.readline()
        m = re.search(r"page on (http://\S+/);", line)
        assert m, f"ethercat serve printed no page URL: {line!r}"
        yield m.group(1)
    finally:
        if proc:
            proc.terminate()
            proc.wait(timeout=10)
        subprocess.run(["ip", "link", "del", a], capture_output=True)


def line_rows(b):
    """The line view's rows, read in one go (the view redraws twice a second)."""
    return b.execute_script(
        "return [...document.querySelectorAll('#line tbody tr')].map(r => "
        "({position: r.dataset.position, state: r.dataset.state, cells: [...r.cells].map(c => c.textContent)}))"
    )


def test_the_line_view_shows_the_slaves_and_their_state(browser, line_url):
    browser.get(line_url)
    rows = wait_for(browser, "two slaves in the line view", lambda b: (r := line_rows(b)) and len(r) == 2 and r)
    assert [r["position"] for r in rows] == ["1", "2"]
    assert [r["state"] for r in rows] == ["INIT", "INIT"]
    cells = [r["cells"] for r in rows]
    assert all(c[1] not in ("", "–") for c in cells), cells  # the SII's names
    assert all("0000h No error" in c[5] for c in cells), cells
    assert "EtherCAT line: 2 slave(s)" in text(browser, "conn")
    # The CAN panels are not shown on a line's page.
    assert not browser.find_element(By.ID, "nodes-panel").is_displayed()
    assert "frames" in text(browser, "line-stats")
    shot(browser, "web-ethercat-line.png")
