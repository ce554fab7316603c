"""The page of `drivebus serve --http` in headless Chromium, used by clicking.

Against `serve --drive akd:1 --drive dds6:2`: the node table lists both
drives, the drive panel enables and moves node 1, the scope's legend
shows the position reaching the target, the object form writes and reads
back a value. Screenshots go to $SCREENSHOTS when set.
"""

import os
import re
import subprocess

import pytest
from selenium import webdriver
from selenium.webdriver.chrome.options import Options
from selenium.webdriver.chrome.service import Service
from selenium.webdriver.common.by import By
from selenium.webdriver.support.ui import Select, WebDriverWait

BIN = os.environ["DRIVEBUS_BIN"]
# Generous: the CI host is loaded; a wait returns as soon as its condition holds.
WAIT_S = 30


def serve_page(*args):
    """`drivebus serve ARGS --http` on free ports: yields the page's URL,
    then stops the server (it must exit cleanly). The browser tests'
    page fixtures are this with their drives."""
    proc = subprocess.Popen(
        [BIN, "serve", "--listen", "127.0.0.1:0", *args, "--http", "127.0.0.1:0"],
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
    )
    line = proc.stdout.readline()
    m = re.search(r"page on (http://\S+/)", line)
    assert m, f"serve printed no page URL: {line!r}"
    yield m.group(1)
    proc.terminate()
    assert proc.wait(timeout=10) == 0


@pytest.fixture(scope="module")
def page_url():
    yield from serve_page("--drive", "akd:1", "--drive", "dds6:2")


@pytest.fixture(scope="module")
def browser():
    opts = Options()
    opts.binary_location = "/usr/bin/chromium"
    for a in ("--headless=new", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage", "--window-size=1280,1080"):
        opts.add_argument(a)
    driver = webdriver.Chrome(service=Service("/usr/bin/chromedriver"), options=opts)
    yield driver
    driver.quit()


def wait_for(browser, what, cond):
    try:
        return WebDriverWait(browser, WAIT_S, poll_frequency=0.1).until(lambda b: cond(b))
    except Exception as e:  # selenium's TimeoutException says nothing of what
        seen = {i: text(browser, i) for i in ("conn", "drive-state", "drive-out", "motion-out", "sdo-out", "legend", "trig-state")}
        raise AssertionError(f"{what}: not within {WAIT_S} s; the page shows {seen}") from e


def text(browser, id_):
    return browser.find_element(By.ID, id_).text


def shot(browser, name):
    d = os.environ.get("SCREENSHOTS")
    if d:
        browser.save_screenshot(os.path.join(d, name))


def click_action(browser, action):
    browser.find_element(By.CSS_SELECTOR, f'button[data-action="{action}"]').click()


def test_the_node_table_lists_both_drives(browser, page_url):
    browser.get(page_url)
    rows = wait_for(
        browser,
        "two rows in the node table",
        lambda b: (r := b.find_elements(By.CSS_SELECTOR, "#nodes tbody tr")) and len(r) == 2 and r,
    )
    cells = [r.find_elements(By.TAG_NAME, "td")[0].text for r in rows]
    assert cells == ["1", "2"]
    assert "2 node(s)" in text(browser, "conn")
    # The bus load of the last second: the page's own SDO polls are on the
    # bus; serve runs unpaced here, so no bitrate and no load.
    load = wait_for(browser, "the bus load shown", lambda b: "frames/s" in (t := text(b, "bus-load")) and t)
    assert "load unknown" in load, load


def test_enable_and_move_by_clicking_and_the_scope_shows_the_target(browser, page_url):
    browser.get(page_url)
    wait_for(browser, "drive 1 selectable", lambda b: Select(b.find_element(By.ID, "drive-node")).options)
    Select(browser.find_element(By.ID, "drive-node")).select_by_value("1")
    click_action(browser, "enable")
    wait_for(browser, "the drive panel shows operation enabled", lambda b: "operation enabled" in text(b, "drive-state"))
    for id_, v in (("scope-window", "3"), ("move-target", "4000"), ("move-velocity", "20000"), ("move-acceleration", "100000")):
        el = browser.find_element(By.ID, id_)
        el.clear()
        el.send_keys(v)
    browser.find_element(By.CSS_SELECTOR, '#move button[type="submit"]').click()

    def position(b):
        m = re.search(r"position (-?\d+)", text(b, "drive-state"))
        return m and abs(int(m.group(1)) - 4000) <= 20

    wait_for(browser, "the drive panel's position reaches 4000", position)
    # The scope's default channels are 1:6064 and 1:606C; its legend shows
    # the last sample of each.
    def legend_at_target(b):
        m = re.search(r"node 1 6064h:0 = (-?\d+)", text(b, "legend"))
        return m and abs(int(m.group(1)) - 4000) <= 20

    wait_for(browser, "the scope's 6064h trace reaches 4000", legend_at_target)
    wait_for(browser, "the motion's end reported", lambda b: "target_reached" in text(b, "motion-out"))
    shot(browser, "web-scope.png")
    click_action(browser, "disable")
    wait_for(browser, "the drive panel leaves operation enabled", lambda b: "operation enabled" not in text(b, "drive-state"))


def diagram_state(browser):
    """The state the drive panel's CiA 402 diagram highlights (its data attribute and the one box marked)."""
    svg = browser.find_element(By.ID, "state-diagram")
    marked = [g.get_attribute("data-state-name") for g in svg.find_elements(By.CSS_SELECTOR, "g.state.current")]
    return svg.get_attribute("data-state"), marked


def test_the_state_diagram_follows_enable_and_disable(browser, page_url):
    browser.get(page_url)
    wait_for(browser, "drive 1 selectable", lambda b: Select(b.find_element(By.ID, "drive-node")).options)
    Select(browser.find_element(By.ID, "drive-node")).select_by_value("1")
    svg = browser.find_element(By.ID, "state-diagram")
    names = [g.get_attribute("data-state-name") for g in svg.find_elements(By.CSS_SELECTOR, "g.state")]
    assert len(names) == 8 and "quick stop active" in names and "fault reaction active" in names, names
    # Transitions 0..16 of CiA 402, each drawn once.
    nums = sorted(int(p.get_attribute("data-transition")) for p in svg.find_elements(By.CSS_SELECTOR, "path.transition"))
    assert nums == list(range(17)), nums
    # The earlier test left it disabled (ready to switch on).
    wait_for(browser, "the diagram shows ready to switch on", lambda b: diagram_state(b) == ("ready to switch on", ["ready to switch on"]))
    click_action(browser, "enable")
    wait_for(browser, "the diagram shows operation enabled", lambda b: diagram_state(b) == ("operation enabled", ["operation enabled"]))
    click_action(browser, "quick-stop")
    wait_for(browser, "the diagram shows quick stop active", lambda b: diagram_state(b)[0] in ("quick stop active", "switch on disabled"))
    click_action(browser, "disable")
    wait_for(browser, "the diagram leaves operation enabled", lambda b: diagram_state(b)[0] not in ("operation enabled", "quick stop active"))


def set_fields(browser, pairs):
    for id_, v in pairs:
        el = browser.find_element(By.ID, id_)
        el.clear()
        el.send_keys(v)


def scope_last(browser, key):
    """The newest sample the scope buffered for channel `key` ("1:6064:0"), via the page's hook."""
    return browser.execute_script(
        "const s = window.drivebus.samples()[arguments[0]]; return s && s.length ? s[s.length - 1][1] : null;", key
    )


def drive_position(browser):
    m = re.search(r"position (-?\d+)", text(browser, "drive-state"))
    return m and int(m.group(1))


def test_enable_home_and_move_by_clicking(browser, page_url):
    browser.get(page_url)
    wait_for(browser, "drive 1 selectable", lambda b: Select(b.find_element(By.ID, "drive-node")).options)
    Select(browser.find_element(By.ID, "drive-node")).select_by_value("1")
    # The AKD has no 60E3h: the methods are its manual's, 35 (current position) among them.
    methods = wait_for(
        browser,
        "the homing methods listed",
        lambda b: [o.get_attribute("value") for o in Select(b.find_element(By.ID, "home-method")).options],
    )
    assert "35" in methods and "-7" in methods, methods
    assert "akd manual" in text(browser, "home-source")
    wait_for(browser, "the diagram shows a disabled drive", lambda b: diagram_state(b)[0] in ("switch on disabled", "ready to switch on"))
    click_action(browser, "enable")
    wait_for(browser, "the diagram shows operation enabled", lambda b: diagram_state(b)[0] == "operation enabled")
    set_fields(browser, (("scope-window", "5"), ("move-target", "1500"), ("move-velocity", "20000"), ("move-acceleration", "100000")))
    browser.find_element(By.CSS_SELECTOR, '#move button[type="submit"]').click()
    wait_for(browser, "the scope's 6064h reaches 1500", lambda b: (v := scope_last(b, "1:6064:0")) is not None and abs(v - 1500) <= 20)
    # Homing on the current position (35): the position becomes the home offset, 0.
    Select(browser.find_element(By.ID, "home-method")).select_by_value("35")
    browser.find_element(By.CSS_SELECTOR, '#home button[type="submit"]').click()
    wait_for(browser, "homing attained", lambda b: "homing_attained" in text(b, "motion-out"))
    wait_for(browser, "the scope's 6064h at 0 after homing", lambda b: (v := scope_last(b, "1:6064:0")) is not None and abs(v) <= 20)
    set_fields(browser, (("move-target", "3000"),))
    browser.find_element(By.CSS_SELECTOR, '#move button[type="submit"]').click()
    wait_for(browser, "the scope's 6064h reaches 3000", lambda b: (v := scope_last(b, "1:6064:0")) is not None and abs(v - 3000) <= 20)
    wait_for(browser, "the move's end reported", lambda b: "target_reached" in text(b, "motion-out"))
    click_action(browser, "disable")
    wait_for(browser, "the diagram leaves operation enabled", lambda b: diagram_state(b)[0] == "ready to switch on")


def test_a_following_error_shows_the_manuals_emcy_text(browser, page_url):
    browser.get(page_url)
    wait_for(browser, "node 1 in the forms", lambda b: Select(b.find_element(By.ID, "sdo-node")).options)
    Select(browser.find_element(By.ID, "sdo-node")).select_by_value("1")
    Select(browser.find_element(By.ID, "drive-node")).select_by_value("1")
    before = browser.execute_script("return fetch('/api/nodes/1/sdo/6065/0').then(r => r.json()).then(j => j.value)")
    # A following error window of 1 increment: a fast move trips it.
    set_fields(browser, (("sdo-index", "6065"), ("sdo-sub", "0"), ("sdo-type", ""), ("sdo-value", "1")))
    browser.find_element(By.ID, "sdo-write").click()
    wait_for(browser, "the window written", lambda b: '"written": true' in text(b, "sdo-out"))
    click_action(browser, "enable")
    wait_for(browser, "the diagram shows operation enabled", lambda b: diagram_state(b)[0] == "operation enabled")
    set_fields(browser, (("move-target", "40000"), ("move-velocity", "40000"), ("move-acceleration", "200000")))
    browser.find_element(By.CSS_SELECTOR, '#move button[type="submit"]').click()
    row = wait_for(
        browser,
        "an EMCY row for 8611h from node 1",
        lambda b: next((r for r in b.find_elements(By.CSS_SELECTOR, '#emcy li[data-code="8611"][data-node="1"]')), None),
    )
    # AKD manual, CANopen EMCY table: 8611h is F439, "Following error (user)".
    assert "8611h" in row.text and "Following error (user)" in row.text and "F439" in row.text, row.text
    wait_for(browser, "the diagram shows fault", lambda b: diagram_state(b)[0] == "fault")
    shot(browser, "web-emcy.png")
    click_action(browser, "fault-reset")
    wait_for(browser, "the diagram shows switch on disabled", lambda b: diagram_state(b)[0] == "switch on disabled")
    # The window as it was, for the tests after this one.
    restored = browser.execute_script(
        "return fetch('/api/nodes/1/sdo/6065/0', {method: 'PUT', headers: {'Content-Type': 'application/json'},"
        " body: JSON.stringify({value: arguments[0]})}).then(r => r.status)",
        before,
    )
    assert restored == 200


def test_the_object_form_writes_and_reads_back(browser, page_url):
    browser.get(page_url)
    wait_for(browser, "node 1 in the object form", lambda b: Select(b.find_element(By.ID, "sdo-node")).options)
    Select(browser.find_element(By.ID, "sdo-node")).select_by_value("1")
    for id_, v in (("sdo-index", "profile_velocity"), ("sdo-sub", "0"), ("sdo-value", "12345")):
        el = browser.find_element(By.ID, id_)
        el.clear()
        el.send_keys(v)
    browser.find_element(By.ID, "sdo-write").click()
    wait_for(browser, "the write confirmed", lambda b: "12345" in text(b, "sdo-out"))
    browser.find_element(By.ID, "sdo-value").clear()
    browser.find_element(By.ID, "sdo-read").click()
    wait_for(
        browser,
        "the read-back value in the form",
        lambda b: b.find_element(By.ID, "sdo-value").get_attribute("value") == "12345",
    )


def test_a_bad_index_shows_the_reason_and_changes_nothing(browser, page_url):
    browser.get(page_url)
    wait_for(browser, "node 1 in the object form", lambda b: Select(b.find_element(By.ID, "sdo-node")).options)
    el = browser.find_element(By.ID, "sdo-index")
    el.clear()
    el.send_keys("nonsense_object")
    browser.find_element(By.ID, "sdo-read").click()
    wait_for(browser, "an error naming the cause", lambda b: "nonsense_object" in text(b, "sdo-out"))


def scope_js(browser, expr, *args):
    return browser.execute_script("return " + expr, *args)


def subscribe_scope(browser, chans, period="10", window="2"):
    set_fields(browser, (("scope-channels", chans), ("scope-period", period), ("scope-window", window)))
    browser.find_element(By.CSS_SELECTOR, '#scope-form button[type="submit"]').click()


def move_to(browser, target):
    set_fields(browser, (("move-target", str(target)), ("move-velocity", "20000"), ("move-acceleration", "100000")))
    browser.find_element(By.CSS_SELECTOR, '#move button[type="submit"]').click()


def test_the_scope_triggers_on_a_level_edge_and_a_statusword_bit(browser, page_url):
    browser.get(page_url)
    wait_for(browser, "drive 1 selectable", lambda b: Select(b.find_element(By.ID, "drive-node")).options)
    Select(browser.find_element(By.ID, "drive-node")).select_by_value("1")
    subscribe_scope(browser, "1:6064, 1:6041")
    sources = lambda b: [o.get_attribute("value") for o in Select(b.find_element(By.ID, "trig-source")).options]
    wait_for(browser, "both channels as trigger sources", lambda b: {"1:6064:0", "1:6041:0"} <= set(sources(b)))
    click_action(browser, "enable")
    wait_for(browser, "operation enabled", lambda b: diagram_state(b)[0] == "operation enabled")
    move_to(browser, 0)
    wait_for(browser, "the position at 0", lambda b: (v := scope_last(b, "1:6064:0")) is not None and abs(v) <= 20)
    # Level 1000, rising edge on the position.
    Select(browser.find_element(By.ID, "trig-source")).select_by_value("1:6064:0")
    Select(browser.find_element(By.ID, "trig-kind")).select_by_value("rising")
    set_fields(browser, (("trig-level", "1000"),))
    browser.find_element(By.ID, "trig-arm").click()
    assert browser.find_element(By.ID, "trig-state").get_attribute("data-state") == "armed"
    assert scope_js(browser, "window.drivebus.capture()") is None
    move_to(browser, 3000)
    wait_for(browser, "triggered", lambda b: b.find_element(By.ID, "trig-state").get_attribute("data-state") in ("triggered", "done"))
    wait_for(browser, "the capture done", lambda b: b.find_element(By.ID, "trig-state").get_attribute("data-state") == "done")
    t_trig = scope_js(browser, "window.drivebus.trigger().t")
    cap = scope_js(browser, "window.drivebus.capture()")["1:6064:0"]
    # The capture starts at the triggering sample: the first at or above the level.
    assert cap[0][0] == t_trig and cap[0][1] >= 1000, cap[:3]
    assert all(t >= t_trig for t, _ in cap)
    live = scope_js(browser, "window.drivebus.samples()")["1:6064:0"]
    before = [v for t, v in live if t < t_trig]
    assert before and before[-1] < 1000, before[-3:]
    # The capture holds one window (2 s) and is frozen on the canvas: Δt of the cursors is half of it.
    assert cap[-1][0] - t_trig >= 2000 - 50
    assert browser.find_element(By.ID, "cursors").get_attribute("data-dt") == "1000.000"
    # Statusword bit 2 (operation enabled) cleared: a disable triggers.
    Select(browser.find_element(By.ID, "trig-source")).select_by_value("1:6041:0")
    Select(browser.find_element(By.ID, "trig-kind")).select_by_value("bit-clear")
    set_fields(browser, (("trig-level", "2"),))
    browser.find_element(By.ID, "trig-arm").click()
    assert browser.find_element(By.ID, "trig-state").get_attribute("data-state") == "armed"
    click_action(browser, "disable")
    wait_for(browser, "the bit trigger fired", lambda b: b.find_element(By.ID, "trig-state").get_attribute("data-state") in ("triggered", "done"))
    sw = scope_js(browser, "window.drivebus.capture()")["1:6041:0"]
    assert sw[0][1] & 4 == 0 and sw[0][0] == scope_js(browser, "window.drivebus.trigger().t"), sw[:3]
    browser.find_element(By.ID, "trig-off").click()
    assert browser.find_element(By.ID, "trig-state").get_attribute("data-state") == "off"


def test_the_scope_exports_csv_and_png(browser, page_url):
    browser.get(page_url)
    wait_for(browser, "drive 1 selectable", lambda b: Select(b.find_element(By.ID, "drive-node")).options)
    subscribe_scope(browser, "1:6064, 1:6041", period="20", window="1")
    wait_for(browser, "samples of both channels", lambda b: all(
        len(scope_js(b, "window.drivebus.samples()").get(k, [])) >= 10 for k in ("1:6064:0", "1:6041:0")))
    csv = scope_js(browser, "window.drivebus.csv()")
    lines = csv.splitlines()
    assert lines[0] == "t_ms,node,index,sub,value", lines[:2]
    rows = [line.split(",") for line in lines[1:]]
    assert len(rows) >= 20
    assert {(r[1], r[2], r[3]) for r in rows} == {("1", "6064", "0"), ("1", "6041", "0")}
    times = [float(r[0]) for r in rows]
    assert times == sorted(times) and times[-1] - times[0] <= 1000
    # Statusword rows are integers the drive reported (switch on disabled or ready to switch on: bit 6 or bit 0).
    assert all(int(r[4]) & 0x41 for r in rows if r[2] == "6041")
    assert scope_js(browser, "window.drivebus.png()").startswith("data:image/png;base64,")


def test_the_dictionary_browser_searches_and_edits(browser, page_url):
    browser.get(page_url)
    wait_for(browser, "node 1 in the object form", lambda b: Select(b.find_element(By.ID, "sdo-node")).options)
    Select(browser.find_element(By.ID, "sdo-node")).select_by_value("1")
    set_fields(browser, (("od-q", "latch control"),))
    browser.find_element(By.CSS_SELECTOR, '#od-search button[type="submit"]').click()
    row = wait_for(browser, "20A4h listed", lambda b: next(iter(b.find_elements(By.CSS_SELECTOR, '#od tbody tr[data-index="20A4"]')), None))
    assert "UNSIGNED16" in row.text and "rw" in row.text and "0..15" in row.text, row.text
    row.click()
    wait_for(browser, "the row read into the form", lambda b: '"index": "20A4"' in text(b, "sdo-out"))
    set_fields(browser, (("sdo-value", "3"),))
    browser.find_element(By.ID, "sdo-write").click()
    wait_for(browser, "the write confirmed", lambda b: '"written": true' in text(b, "sdo-out"))
    set_fields(browser, (("sdo-value", "16"),))
    browser.find_element(By.ID, "sdo-write").click()
    wait_for(browser, "the limit named", lambda b: "the EDS allows 0 to 15" in text(b, "sdo-out"))
    browser.find_element(By.ID, "sdo-read").click()
    wait_for(browser, "still 3", lambda b: b.find_element(By.ID, "sdo-value").get_attribute("value") == "3")


def test_the_page_buffers_are_bounded(browser, page_url):
    browser.get(page_url)
    wait_for(browser, "the scope subscribed", lambda b: scope_last(b, "1:6064:0") is not None)
    set_fields(browser, (("scope-window", "10"),))
    # Samples from a long run age out: at most two windows (20 s at 1 kHz) are kept.
    kept = browser.execute_script(
        "for (let i = 0; i < 60000; i++) scopeSample({node: 9, index: 'AGED', sub: 0, t: 1e7 + i, value: i});"
        "return window.drivebus.samples()['9:AGED:0'].length;"
    )
    assert kept <= 20000 + 1024, kept
    # More within the window than the page keeps: the oldest dropped and counted.
    kept = browser.execute_script(
        "for (let i = 0; i < 130000; i++) scopeSample({node: 9, index: 'DENSE', sub: 0, t: 2e7 + i / 100, value: i});"
        "return window.drivebus.samples()['9:DENSE:0'].length;"
    )
    assert kept <= 120000, kept
    wait_for(browser, "the page's drops shown", lambda b: "dropped by the page" in text(b, "page-dropped"))


def test_usable_at_1280x720(browser, page_url):
    """At 1280×720 nothing is wider than the window (no sideways
    scrolling), and every panel, button and the scope's canvas has room."""
    browser.set_window_size(1280, 720)
    try:
        browser.get(page_url)
        wait_for(browser, "the node table filled", lambda b: len(b.find_elements(By.CSS_SELECTOR, "#nodes tbody tr")) == 2)
        inner = browser.execute_script("return window.innerWidth")
        assert inner <= 1280
        wide = browser.execute_script("return document.documentElement.scrollWidth")
        assert wide <= inner, f"the page is {wide} px wide in a {inner} px window"
        sizes = browser.execute_script(
            """return [...document.querySelectorAll('body > section, body > main > section')]
                 .filter(s => getComputedStyle(s).display !== 'none')
                 .map(s => { const r = s.getBoundingClientRect(); return [s.id, r.left, r.right, r.width]; })"""
        )
        assert len(sizes) >= 6, sizes
        for sid, left, right, width in sizes:
            assert left >= 0 and right <= inner + 0.5 and width > 200, (sid, left, right, width)
        cramped = browser.execute_script(
            """return [...document.querySelectorAll('section button')]
                 .filter(b => getComputedStyle(b).display !== 'none' && b.offsetParent !== null)
                 .filter(b => { const r = b.getBoundingClientRect(); return r.width < 16 || r.height < 12 || r.right > window.innerWidth; })
                 .map(b => b.id || b.textContent)"""
        )
        assert not cramped, cramped
        canvas = browser.execute_script("const c = document.querySelector('#scope-panel canvas').getBoundingClientRect(); return [c.width, c.right]")
        assert canvas[0] >= 600 and canvas[1] <= inner + 0.5, canvas
    finally:
        browser.set_window_size(1280, 1080)
