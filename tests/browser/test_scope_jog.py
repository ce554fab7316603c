"""The scope's pan and zoom, jog and the CSP sine generator, in headless Chromium.

Against `serve --drive akd:1 --drive dds6:2` (the fixtures of test_page).
"""

import time

from selenium.webdriver.common.action_chains import ActionChains
from selenium.webdriver.common.actions.wheel_input import ScrollOrigin
from selenium.webdriver.common.by import By

from selenium.webdriver.support.ui import Select

from test_page import (  # noqa: F401 (fixtures)
    browser,
    click_action,
    drive_position,
    page_url,
    set_fields,
    subscribe_scope,
    text,
    wait_for,
)


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


def enabled_drive_1(browser, page_url):
    browser.get(page_url)
    wait_for(browser, "drive 1 selectable", lambda b: Select(b.find_element(By.ID, "drive-node")).options)
    Select(browser.find_element(By.ID, "drive-node")).select_by_value("1")
    click_action(browser, "enable")
    wait_for(browser, "operation enabled", lambda b: "operation enabled" in text(b, "drive-state"))


def settled_position(browser):
    """The drive panel's position once two readings 0.4 s apart agree."""

    def still(b):
        p = drive_position(b)
        time.sleep(0.4)
        return p is not None and p == drive_position(b) and (p,)

    return wait_for(browser, "the drive at rest", still)[0]


def test_jog_runs_while_held_and_stops_on_release_leaving_and_hiding(browser, page_url):
    enabled_drive_1(browser, page_url)
    set_fields(browser, (("jog-speed", "20000"),))
    p0 = settled_position(browser)
    plus = browser.find_element(By.ID, "jog-plus")
    browser.execute_script("arguments[0].scrollIntoView({block: 'center'})", plus)
    ActionChains(browser).move_to_element(plus).click_and_hold().perform()
    wait_for(browser, "jogging shown", lambda b: "jogging at 20000" in text(b, "jog-state"))
    wait_for(browser, "the position rises while held", lambda b: (p := drive_position(b)) is not None and p > p0 + 5000)
    ActionChains(browser).release().perform()
    wait_for(browser, "the release reported", lambda b: "jog released" in text(b, "motion-out"))
    p1 = settled_position(browser)
    assert p1 > p0 + 5000
    # Held, then the mouse leaves the button: stopped too.
    minus = browser.find_element(By.ID, "jog-minus")
    ActionChains(browser).move_to_element(minus).click_and_hold().perform()
    wait_for(browser, "the position falls while held", lambda b: (p := drive_position(b)) is not None and p < p1 - 3000)
    ActionChains(browser).move_to_element(browser.find_element(By.ID, "jog-speed")).perform()
    wait_for(browser, "stopped on leaving the button", lambda b: text(b, "jog-state") == "")
    p2 = settled_position(browser)
    time.sleep(0.6)
    assert drive_position(browser) == p2
    ActionChains(browser).release().perform()
    # Held, then the page is hidden (its pagehide event): stopped too.
    ActionChains(browser).move_to_element(plus).click_and_hold().perform()
    wait_for(browser, "the position rises while held", lambda b: (p := drive_position(b)) is not None and p > p2 + 3000)
    browser.execute_script("window.dispatchEvent(new Event('pagehide'))")
    wait_for(browser, "stopped on hiding", lambda b: text(b, "jog-state") == "" and "jog released" in text(b, "motion-out"))
    p3 = settled_position(browser)
    time.sleep(0.6)
    assert drive_position(browser) == p3
    ActionChains(browser).release().perform()
    click_action(browser, "disable")


def test_csp_sine_is_seen_in_the_scope(browser, page_url):
    """From -5000 a sine of amplitude 5000 swings to +5000 and back: the scope's trace crosses 0 both ways."""
    enabled_drive_1(browser, page_url)
    subscribe_scope(browser, "1:6064", period="10", window="10")
    set_fields(browser, (("move-target", "-5000"), ("move-velocity", "50000"), ("move-acceleration", "200000")))
    browser.find_element(By.CSS_SELECTOR, '#move button[type="submit"]').click()
    wait_for(browser, "at -5000", lambda b: "target_reached" in text(b, "motion-out") and abs((drive_position(b) or 0) + 5000) <= 20)
    set_fields(browser, (("sine-amplitude", "5000"), ("sine-period", "1000"), ("sine-duration", "2000")))
    t0 = js(browser, "(window.drivebus.samples()['1:6064:0'] || []).slice(-1)[0][0]")
    browser.find_element(By.CSS_SELECTOR, '#sine button[type="submit"]').click()
    wait_for(browser, "the sine's end reported", lambda b: "sine completed" in text(b, "motion-out"))
    trace = [v for t, v in js(browser, "window.drivebus.samples()['1:6064:0']") if t >= t0]
    ups = sum(1 for a, b in zip(trace, trace[1:]) if a < 0 <= b)
    downs = sum(1 for a, b in zip(trace, trace[1:]) if a >= 0 > b)
    assert ups >= 2 and downs >= 2, (ups, downs, min(trace), max(trace))
    assert max(trace) > 4000 and min(trace) < -4000
    click_action(browser, "disable")


def test_four_channels_at_1_khz_without_drops():
    """Issue 19 §5 briefly (the full 10 minutes: scope_rate.py, BENCHMARKS.md): no drops, no reconnect; no times asserted."""
    import os

    import scope_rate

    bench = scope_rate.Bench(os.environ["DRIVEBUS_BIN"])
    try:
        r = scope_rate.run_rate(bench, 5, 2)
    finally:
        bench.close()
    assert sorted(r["rate_per_channel"]) == ["1:6041:0", "1:6061:0", "1:6064:0", "1:606C:0"], r
    assert all(v > 0 for v in r["rate_per_channel"].values()), r
    assert (r["server_dropped"], r["page_dropped"], r["reconnected"]) == (0, 0, False), r
    assert not scope_rate.dropped(r), r
