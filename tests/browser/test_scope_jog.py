"""The scope's pan and zoom in headless Chromium.

Against `serve --drive akd:1 --drive dds6:2` (the fixtures of test_page).
"""

import time

from selenium.webdriver.common.action_chains import ActionChains
from selenium.webdriver.common.actions.wheel_input import ScrollOrigin
from selenium.webdriver.common.by import By

from test_page import browser, page_url, set_fields, subscribe_scope, wait_for  # noqa: F401 (fixtures)


def js(browser, expr):
    return browser.execute_script("return " + expr)


def view(browser):
    return js(browser, "window.drivebus.view()")


def newest_t(browser, key):
    return js(browser, f"(window.drivebus.samples()['{key}'] || []).slice(-1).map(s => s[0])[0] ?? null")


def test_wheel_zooms_drag_pans_and_live_returns(browser, page_url):
    browser.get(page_url)
    subscribe_scope(browser, "1:6064, 1:6041", period="10", window="2")
    wait_for(browser, "samples in the scope", lambda b: newest_t(b, "1:6064:0") is not None)
    v = view(browser)
    assert v["live"] and v["w"] == 2000, v
    canvas = browser.find_element(By.ID, "scope")
    # Zoom in at the middle (between the cursors at 25 % and 75 %): the span shrinks.
    ActionChains(browser).scroll_from_origin(ScrollOrigin.from_element(canvas), 0, -300).perform()
    wait_for(browser, "the view paused and zoomed in", lambda b: not view(b)["live"] and view(b)["w"] < 2000)
    zoomed = view(browser)
    # Zoomed around the mouse: the time under the middle of the canvas stays in the middle.
    t_before = newest_t(browser, "1:6064:0")
    time.sleep(0.5)
    # Recording goes on, the view does not move.
    assert newest_t(browser, "1:6064:0") > t_before
    assert view(browser) == zoomed
    assert not js(browser, "document.getElementById('scope-live').disabled")
    # A drag to the right pans to earlier times by the dragged fraction of the span.
    width = canvas.size["width"]
    ActionChains(browser).move_to_element(canvas).click_and_hold().move_by_offset(width // 10, 0).release().perform()
    panned = view(browser)
    assert panned["w"] == zoomed["w"]
    shift = (zoomed["tMin"] - panned["tMin"]) / zoomed["w"]
    assert 0.05 < shift < 0.15, (zoomed, panned)
    # Double-click: live again, one window wide, following the newest samples.
    ActionChains(browser).double_click(canvas).perform()
    wait_for(browser, "live again", lambda b: view(b)["live"] and view(b)["w"] == 2000)
    live = view(browser)
    assert abs(live["tMin"] + live["w"] - newest_t(browser, "1:6064:0")) < 200, live
    # The button does the same.
    ActionChains(browser).scroll_from_origin(ScrollOrigin.from_element(canvas), 0, -300).perform()
    wait_for(browser, "paused again", lambda b: not view(b)["live"])
    browser.find_element(By.ID, "scope-live").click()
    wait_for(browser, "live by the button", lambda b: view(b)["live"])
    set_fields(browser, (("scope-window", "10"),))

