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


@pytest.fixture(scope="module")
def page_url():
    proc = subprocess.Popen(
        [BIN, "serve", "--listen", "127.0.0.1:0", "--drive", "akd:1", "--drive", "dds6:2", "--http", "127.0.0.1:0"],
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
        seen = {i: text(browser, i) for i in ("conn", "drive-state", "drive-out", "sdo-out", "legend")}
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
    wait_for(browser, "the motion's end reported", lambda b: "target_reached" in text(b, "drive-out"))
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
    wait_for(browser, "homing attained", lambda b: "homing_attained" in text(b, "drive-out"))
    wait_for(browser, "the scope's 6064h at 0 after homing", lambda b: (v := scope_last(b, "1:6064:0")) is not None and abs(v) <= 20)
    set_fields(browser, (("move-target", "3000"),))
    browser.find_element(By.CSS_SELECTOR, '#move button[type="submit"]').click()
    wait_for(browser, "the scope's 6064h reaches 3000", lambda b: (v := scope_last(b, "1:6064:0")) is not None and abs(v - 3000) <= 20)
    wait_for(browser, "the move's end reported", lambda b: "target_reached" in text(b, "drive-out"))
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
