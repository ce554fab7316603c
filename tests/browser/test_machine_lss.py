"""The machine panel and the LSS panel of the page, used by clicking.

Against `serve --drive akd:1 --drive dds6:2`: the machine panel's encoder
fault puts node 1 in FAULT in the overview and its EMCY appears decoded
in the EMCY log; clear and fault reset bring it back; tripping the
positive limit switch lights the drive panel's lamp; a digital input is
set and listed; a value out of range shows the API's reason.

Against `serve --drive generic:5 --lss-slave ...` (an unconfigured LSS
slave): scan finds it, inquire reads it unconfigured, configure gives it
node-ID 9 and node 9 appears in the overview; a second configure of "the
only unconfigured slave" shows the API's refusal.
"""

import pytest
from selenium.common.exceptions import StaleElementReferenceException
from selenium.webdriver.common.by import By
from selenium.webdriver.support.ui import Select, WebDriverWait

from test_page import browser, click_action, serve_page, shot  # noqa: F401 (browser is a fixture)

WAIT_S = 30
IDS = ("conn", "drive-state", "drive-out", "machine-out", "machine-inputs", "emcy", "lss-out", "nodes")


def wait_for(browser, what, cond):
    try:
        # The overview and the logs are rebuilt as they refresh: a row read
        # while replaced is read again.
        wait = WebDriverWait(browser, WAIT_S, poll_frequency=0.1, ignored_exceptions=(StaleElementReferenceException,))
        return wait.until(lambda b: cond(b))
    except Exception as e:
        seen = {i: browser.find_element(By.ID, i).text for i in IDS}
        raise AssertionError(f"{what}: not within {WAIT_S} s; the page shows {seen}") from e


def text(browser, id_):
    return browser.find_element(By.ID, id_).text


def click(browser, css):
    browser.find_element(By.CSS_SELECTOR, css).click()


def overview_state(browser, node):
    """The overview's 402 state cell of `node`, or None when not listed."""
    for r in browser.find_elements(By.CSS_SELECTOR, "#nodes tbody tr"):
        cells = r.find_elements(By.TAG_NAME, "td")
        if cells and cells[0].text == str(node):
            return cells[5].text
    return None


def emcy_of(browser, node):
    return browser.find_elements(By.CSS_SELECTOR, f'#emcy li[data-node="{node}"]')


def active(browser, key):
    return browser.find_element(By.CSS_SELECTOR, f'[data-fault-state="{key}"]').get_attribute("data-active") == "true"


@pytest.fixture(scope="module")
def drives_url():
    yield from serve_page("--drive", "akd:1", "--drive", "dds6:2")


@pytest.fixture(scope="module")
def lss_url():
    yield from serve_page("--drive", "generic:5", "--lss-slave", "0xABC:0x77:3:0x10")


def select_drive(browser, node):
    wait_for(browser, f"drive {node} selectable", lambda b: any(o.get_attribute("value") == str(node) for o in Select(b.find_element(By.ID, "drive-node")).options))
    Select(browser.find_element(By.ID, "drive-node")).select_by_value(str(node))
    wait_for(browser, f"the machine panel on node {node}", lambda b: text(b, "machine-node") == str(node))


def test_an_encoder_fault_clicked_faults_the_drive_and_its_emcy_is_logged(browser, drives_url):
    browser.get(drives_url)
    select_drive(browser, 1)
    click_action(browser, "enable")
    wait_for(browser, "node 1 operation enabled in the overview", lambda b: overview_state(b, 1) == "operation enabled")
    before = len(emcy_of(browser, 1))
    assert not active(browser, "encoder")
    click(browser, '#machine-faults button[data-fault="encoder"]')
    wait_for(browser, "node 1 in FAULT in the overview", lambda b: overview_state(b, 1) == "fault")
    wait_for(browser, "the drive panel in fault", lambda b: text(b, "drive-state").startswith("state: fault "))
    assert overview_state(browser, 2) != "fault", "node 2 is not touched"
    lis = wait_for(browser, "node 1's EMCY in the log", lambda b: (e := emcy_of(b, 1)) and len(e) > before and e)
    # Newest first, decoded: a code with its text.
    assert lis[0].get_attribute("data-text"), lis[0].text
    assert f"{lis[0].get_attribute('data-code')}h" in lis[0].text
    assert active(browser, "encoder")
    assert '"set": true' in text(browser, "machine-out")
    shot(browser, "web-machine-fault.png")
    # The machine fault stays until cleared: a fault reset alone cannot end it.
    click(browser, "#machine-clear")
    wait_for(browser, "the encoder lamp out", lambda b: not active(b, "encoder"))
    assert overview_state(browser, 1) == "fault", "a latched drive fault stays until a fault reset"
    click_action(browser, "fault-reset")
    wait_for(browser, "node 1 out of FAULT", lambda b: overview_state(b, 1) == "switch on disabled")


def test_a_tripped_limit_switch_clicked_lights_the_drive_panel_lamp(browser, drives_url):
    browser.get(drives_url)
    select_drive(browser, 1)
    lamp = lambda b: "on" in b.find_element(By.ID, "sw-positive_limit").get_attribute("class").split()  # noqa: E731
    wait_for(browser, "the switches shown", lambda b: "manufacturer bits" in text(b, "sw-manufacturer"))
    assert not lamp(browser)
    click(browser, '#machine-switches button[data-fault="trip"][data-switch="positive_limit"]')
    wait_for(browser, "the positive limit lamp lit", lamp)
    assert active(browser, "trip:positive_limit")
    assert not active(browser, "trip:negative_limit")
    click(browser, "#machine-clear")
    wait_for(browser, "the positive limit lamp out", lambda b: not lamp(b))
    assert not active(browser, "trip:positive_limit")
    # With a duration the machine ends the trip itself, and the panel's record with it.
    neg = lambda b: "on" in b.find_element(By.ID, "sw-negative_limit").get_attribute("class").split()  # noqa: E731
    browser.find_element(By.ID, "mi-duration").send_keys("1.5")
    click(browser, '#machine-switches button[data-fault="trip"][data-switch="negative_limit"]')
    wait_for(browser, "the negative limit lamp lit", neg)
    assert '"duration": 1.5' in text(browser, "machine-out")
    assert active(browser, "trip:negative_limit")
    wait_for(browser, "the negative limit lamp out after 1.5 s", lambda b: not neg(b) and not active(b, "trip:negative_limit"))


def test_an_input_is_set_and_a_refusal_shows_its_reason(browser, drives_url):
    browser.get(drives_url)
    select_drive(browser, 2)
    Select(browser.find_element(By.ID, "mi-input")).select_by_value("digital")
    for id_, v in (("mi-line", "3"), ("mi-value", "1")):
        el = browser.find_element(By.ID, id_)
        el.clear()
        el.send_keys(v)
    click(browser, "#mi-set")
    wait_for(browser, "digital line 3 listed", lambda b: b.find_elements(By.CSS_SELECTOR, '#machine-inputs li[data-input="digital:3"][data-value="1"]'))
    assert '"node": 2' in text(browser, "machine-out")
    # Analog inputs are lines 1..4: the API refuses 9 and says why.
    Select(browser.find_element(By.ID, "mi-input")).select_by_value("analog")
    el = browser.find_element(By.ID, "mi-line")
    el.clear()
    el.send_keys("9")
    click(browser, "#mi-set")
    wait_for(browser, "the refusal shown", lambda b: "error" in b.find_element(By.ID, "machine-out").get_attribute("class"))
    assert "input" in text(browser, "machine-out")
    assert not browser.find_elements(By.CSS_SELECTOR, '#machine-inputs li[data-input="analog:9"]')


def test_an_unconfigured_lss_slave_is_scanned_and_given_a_node_id_by_clicking(browser, lss_url):
    browser.get(lss_url)
    wait_for(browser, "node 5 in the overview", lambda b: overview_state(b, 5) is not None)
    assert overview_state(browser, 9) is None
    click(browser, "#lss-scan")
    wait_for(browser, "the scan's result", lambda b: "found vendor 0xABC product 0x77 revision 0x3 serial 0x10" in text(b, "lss-out"))
    # The address found fills the form.
    assert Select(browser.find_element(By.ID, "lss-target")).first_selected_option.get_attribute("value") == "address"
    assert browser.find_element(By.ID, "lss-serial").get_attribute("value") == "0x10"
    click(browser, "#lss-inquire")
    wait_for(browser, "the inquiry's result", lambda b: "inquire:" in text(b, "lss-out") and "unconfigured (node-ID FFh)" in text(b, "lss-out"))
    el = browser.find_element(By.ID, "lss-node-id")
    el.clear()
    el.send_keys("9")
    click(browser, "#lss-configure")
    wait_for(browser, "the configure result", lambda b: "configure: node-ID 9 for vendor 0xABC" in text(b, "lss-out"))
    # Configured by address: active at its next NMT reset communication.
    assert "at the slave's next NMT reset communication" in text(browser, "lss-out")
    # The slave configured by address, now back to waiting, starts under its new node-ID.
    wait_for(browser, "node 9 in the overview", lambda b: overview_state(b, 9) is not None)
    shot(browser, "web-lss.png")
    # None unconfigured left: the refusal and its reason, from the API.
    Select(browser.find_element(By.ID, "lss-target")).select_by_value("only")
    el.clear()
    el.send_keys("10")
    click(browser, "#lss-configure")
    wait_for(browser, "the refusal shown", lambda b: "HTTP 404: no unconfigured LSS slave answered" in text(b, "lss-out"))
    assert "error" in browser.find_element(By.ID, "lss-out").get_attribute("class")
    assert browser.find_elements(By.CSS_SELECTOR, '#lss-log li[data-result="error"]')
    assert overview_state(browser, 10) is None
