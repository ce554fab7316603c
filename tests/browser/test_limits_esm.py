"""The drive panel's switch inputs and the EtherCAT line's ESM events in
headless Chromium.

Against `serve --drive generic:5 --http`: the machine API trips the
positive limit switch (60FDh bit 1) and the panel's lamp for it lights,
then goes out when the fault is cleared; the limits line shows 607Dh.

Against `ethercat serve --http` on a veth pair (root: a network
namespace holds the master's end): `drivebus ethercat state preop` moves
the line and the line view lists the ESM events its stream sent.
"""

import json
import os
import re
import subprocess
import urllib.request
import uuid

import pytest
from selenium.webdriver.common.by import By
from selenium.webdriver.support.ui import Select, WebDriverWait

from test_page import BIN, browser, serve_page  # noqa: F401 (browser is a fixture)

WAIT_S = 30


@pytest.fixture(scope="module")
def page_url():
    yield from serve_page("--drive", "generic:5")


def wait_for(browser, what, cond):
    try:
        return WebDriverWait(browser, WAIT_S, poll_frequency=0.1).until(lambda b: cond(b))
    except Exception as e:
        seen = {i: browser.find_element(By.ID, i).text for i in ("conn", "drive-state", "drive-switches", "drive-limits")}
        raise AssertionError(f"{what}: not within {WAIT_S} s; the page shows {seen}") from e


def post(url, path, body):
    req = urllib.request.Request(
        url.rstrip("/") + path, data=json.dumps(body).encode(), headers={"content-type": "application/json"}
    )
    with urllib.request.urlopen(req, timeout=30) as r:
        assert r.status == 200


def lit(browser, key):
    return "on" in browser.find_element(By.ID, "sw-" + key).get_attribute("class").split()


def test_a_tripped_limit_switch_lights_its_lamp(browser, page_url):
    browser.get(page_url)
    wait_for(browser, "drive 5 selectable", lambda b: Select(b.find_element(By.ID, "drive-node")).options)
    Select(browser.find_element(By.ID, "drive-node")).select_by_value("5")
    wait_for(browser, "the limits shown", lambda b: "607Dh" in b.find_element(By.ID, "drive-limits").text)
    assert not lit(browser, "positive_limit")
    assert "manufacturer bits" in browser.find_element(By.ID, "sw-manufacturer").text
    post(page_url, "/api/nodes/5/machine/fault", {"kind": "trip", "switch": "positive_limit"})
    wait_for(browser, "the positive limit lamp lit", lambda b: lit(b, "positive_limit"))
    assert not lit(browser, "negative_limit")
    post(page_url, "/api/nodes/5/machine/fault", {"kind": "clear"})
    wait_for(browser, "the positive limit lamp out", lambda b: not lit(b, "positive_limit"))


@pytest.fixture()
def line_url():
    if os.geteuid() != 0:
        pytest.skip("needs root: a network namespace and a veth pair")
    ns = "dbbr" + uuid.uuid4().hex[:6]
    outer, inner = ns + "a", ns + "b"
    steps = [
        ["netns", "add", ns],
        ["link", "add", outer, "type", "veth", "peer", "name", inner],
        ["link", "set", inner, "netns", ns],
        ["link", "set", outer, "up"],
        ["netns", "exec", ns, "ip", "link", "set", inner, "up"],
    ]
    proc = None
    try:
        for s in steps:
            r = subprocess.run(["ip", *s], capture_output=True, text=True)
            if r.returncode != 0:
                pytest.skip(f"ip {' '.join(s)}: {r.stderr.strip()}")
        proc = subprocess.Popen(
            [BIN, "ethercat", "serve", "--iface", outer, "--drive", "generic", "--drive", "ipos", "--http", "127.0.0.1:0"],
            stdout=subprocess.PIPE,
            stderr=subprocess.DEVNULL,
            text=True,
        )
        line = proc.stdout.readline()
        m = re.search(r"page on (http://[^;\s]+)", line)
        assert m, f"ethercat serve printed no page URL: {line!r}"
        yield m.group(1), ns, inner
    finally:
        if proc:
            proc.kill()
            proc.wait(timeout=10)
        subprocess.run(["ip", "link", "del", outer], capture_output=True)
        subprocess.run(["ip", "netns", "del", ns], capture_output=True)


def test_the_line_view_lists_esm_events_from_the_stream(browser, line_url):
    url, ns, inner = line_url
    browser.get(url)
    wait_for(browser, "two slaves in INIT", lambda b: len(b.find_elements(By.CSS_SELECTOR, '#line tbody tr[data-state="INIT"]')) == 2)
    assert browser.find_elements(By.CSS_SELECTOR, "#line-events li") == []
    r = subprocess.run(["ip", "netns", "exec", ns, BIN, "ethercat", "state", "preop", "--iface", inner], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    for pos in (1, 2):
        li = wait_for(
            browser,
            f"slave {pos}'s PRE-OP event listed",
            lambda b: b.find_elements(By.CSS_SELECTOR, f'#line-events li[data-position="{pos}"][data-state="PRE-OP"]'),
        )
        assert f"slave {pos} INIT → PRE-OP" in li[0].text
    wait_for(browser, "the table in PRE-OP", lambda b: len(b.find_elements(By.CSS_SELECTOR, '#line tbody tr[data-state="PRE-OP"]')) == 2)


def test_the_ethercat_page_reads_an_object_in_the_object_form(browser, line_url):
    """The object form and the dictionary browser on the EtherCAT page:
    the slaves by position, 6041h of the iPOS (position 2) read straight
    from its dictionary, 6064h found in the browser with its type."""
    url, _, _ = line_url
    browser.get(url)
    wait_for(browser, "slave 2 selectable", lambda b: [o for o in Select(b.find_element(By.ID, "sdo-node")).options if o.get_attribute("value") == "2"])
    Select(browser.find_element(By.ID, "sdo-node")).select_by_value("2")
    browser.find_element(By.ID, "sdo-index").clear()
    browser.find_element(By.ID, "sdo-index").send_keys("6041")
    browser.find_element(By.ID, "sdo-read").click()
    out = wait_for(browser, "6041h read", lambda b: '"value"' in b.find_element(By.ID, "sdo-out").text and b.find_element(By.ID, "sdo-out"))
    answer = json.loads(out.text)
    assert (answer["node"], answer["index"], answer["type"]) == (2, "6041", "UNSIGNED16"), answer
    assert isinstance(answer["value"], int)
    assert browser.find_element(By.ID, "sdo-value").get_attribute("value") == str(answer["value"])
    browser.find_element(By.ID, "od-q").send_keys("6064")
    browser.find_element(By.CSS_SELECTOR, "#od-search button").click()
    row = wait_for(browser, "6064h in the dictionary browser", lambda b: b.find_elements(By.CSS_SELECTOR, '#od tbody tr[data-index="6064"]'))
    assert "INTEGER32" in row[0].text


def test_the_scope_plots_6064h_while_a_master_runs_the_line(browser, line_url):
    """The scope on the EtherCAT page: 6064h of the iPOS (position 2)
    subscribed, `drivebus ethercat drive csp-sine` runs it from the
    namespace; the samples come from the process data and move."""
    url, ns, inner = line_url
    browser.get(url)
    wait_for(browser, "the line shown", lambda b: len(b.find_elements(By.CSS_SELECTOR, "#line tbody tr")) == 2)
    channels = browser.find_element(By.ID, "scope-channels")
    channels.clear()
    channels.send_keys("2:6064")
    browser.find_element(By.CSS_SELECTOR, "#scope-form button[type=submit]").click()
    master = subprocess.Popen(
        ["ip", "netns", "exec", ns, BIN, "ethercat", "drive", "--iface", inner, "--slave", "2",
         "csp-sine", "--amplitude", "2000", "--frequency", "2", "--seconds", "3"],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        samples = lambda b: b.execute_script("return window.drivebus.samples()['2:6064:0'] || []")
        try:
            got = wait_for(browser, "6064h moving in the scope", lambda b: (s := samples(b)) and len({v for _, v in s}) > 20 and s)
        except AssertionError as e:
            master.kill()
            raise AssertionError(f"{e}; samples {samples(browser)[-5:]}; master: {master.communicate()[1]}") from e
        assert all(isinstance(v, (int, float)) for _, v in got)
    finally:
        _, err = master.communicate(timeout=60)
    assert master.returncode == 0, err
