"""The demonstration page in a real browser: headless Chromium driven by Selenium drags an
object with the mouse, demonstrates Case 2, plans and executes; the server's state is
checked and a screenshot saved."""

from __future__ import annotations

import json
import os
import shutil
import time

import pytest
import yaml

from tamp.scenarios import path as packaged
from tests.serve.conftest import Served, unity_to_mr, wait_for

CHROMIUM = shutil.which("chromium") or "/usr/bin/chromium"
DRIVER = shutil.which("chromedriver") or "/usr/bin/chromedriver"

pytestmark = pytest.mark.skipif(
    not (os.path.exists(CHROMIUM) and os.path.exists(DRIVER)),
    reason="needs Debian's chromium and chromium-driver (make system-deps installs them)",
)


@pytest.fixture
def browser():
    webdriver = pytest.importorskip("selenium.webdriver")
    options = webdriver.ChromeOptions()
    options.binary_location = CHROMIUM
    for arg in (
        "--headless=new",
        "--no-sandbox",
        "--disable-dev-shm-usage",
        "--window-size=1280,800",
        "--use-angle=swiftshader",
        "--enable-unsafe-swiftshader",
        "--disable-gpu-sandbox",
    ):
        options.add_argument(arg)
    driver = webdriver.Chrome(
        service=webdriver.ChromeService(executable_path=DRIVER), options=options
    )
    driver.set_script_timeout(10)
    yield driver
    driver.quit()


def page_state(driver) -> dict:
    return driver.execute_script(
        "const s = window.demo && window.demo.state; return s ? JSON.parse(JSON.stringify("
        "{phase: s.phase, scene: !!s.scene, steps: s.steps.length, plan: s.plan,"
        " connected: s.connected, events: s.events.length}) ) : null;"
    )


def server_phase(s: Served) -> str:
    return s.thread.call(lambda: s.app.phase)


def test_page_drags_plans_and_executes_case2(browser, tmp_path):
    from selenium.webdriver.common.action_chains import ActionChains
    from selenium.webdriver.common.by import By

    s = Served(demo="case2.yaml", token="page-test-token")
    try:
        browser.get(f"http://127.0.0.1:{s.port}/?token=page-test-token")
        wait_for(lambda: (page_state(browser) or {}).get("scene"), timeout=15, what="scene")
        assert browser.execute_script("return window.demo.webgl"), "WebGL unavailable"

        # One real mouse drag: press on O0 where it is drawn, move, release.
        canvas = browser.find_element(By.CSS_SELECTOR, "#view canvas")
        rect = browser.execute_script(
            "const r = arguments[0].getBoundingClientRect(); return [r.left, r.top, r.width,"
            " r.height];",
            canvas,
        )

        def on_canvas():
            p = browser.execute_script("return window.demo.objectScreen('O0')")
            inside = (
                p and rect[0] < p[0] < rect[0] + rect[2] and rect[1] + 80 < p[1] < rect[1] + rect[3]
            )
            return p if inside else None

        x0, y0 = wait_for(on_canvas, what="O0 drawn on the canvas")
        cx, cy = rect[0] + rect[2] / 2, rect[1] + rect[3] / 2
        chain = ActionChains(browser)
        chain.move_to_element_with_offset(canvas, int(x0 - cx), int(y0 - cy)).click_and_hold()
        for _ in range(5):
            chain.move_by_offset(0, -12)
        chain.release().perform()
        wait_for(
            lambda: s.thread.call(lambda: len(s.app.session.mr_steps)) == 1,
            what="the dragged step on the server",
        )
        dragged = s.thread.call(lambda: s.app.session.steps_json()[0])
        start = browser.execute_script("return window.demo.state.scene.objects[0].mr")
        assert dragged["object"] == "O0" and dragged["mr"] != start
        browser.find_element(By.ID, "undo").click()
        wait_for(lambda: s.thread.call(lambda: len(s.app.session.mr_steps)) == 0, what="undo")

        # Case 2's four moves through the page's hook (the messages a release sends).
        data = yaml.safe_load(packaged("case2.yaml").read_text())
        for step in data["steps"]:
            p = unity_to_mr(step["to"])
            browser.execute_script(
                "window.demo.drag(arguments[0], arguments[1])",
                step["object"],
                [p["x"], p["y"], p["z"]],
            )
        wait_for(lambda: (page_state(browser) or {}).get("steps") == 4, what="four steps")
        browser.find_element(By.ID, "plan").click()
        wait_for(lambda: server_phase(s) == "planned", timeout=15, what="planned")

        # the latched "not planned" result is on the page until the new one arrives
        def planned_on_page():
            plan = (page_state(browser) or {}).get("plan") or {}
            return plan if plan.get("success") is True else None

        plan = wait_for(planned_on_page, timeout=15, what="the plan on the page")
        assert plan["plan"]["order"] == ["G1", "G0", "G3", "G2"]
        browser.find_element(By.ID, "execute").click()
        wait_for(lambda: server_phase(s) == "done", timeout=15, what="done")
        wait_for(lambda: (page_state(browser) or {}).get("phase") == "done", what="page: done")
        doc = json.loads(s.thread.call(lambda: s.server.topics["/tamp/execution"].last))
        assert json.loads(doc["msg"]["data"])["reached"] is True
        time.sleep(0.3)  # let the last frame draw (the screenshot is for people)
        shot = tmp_path / "serve_page.png"
        browser.save_screenshot(str(shot))
        assert shot.stat().st_size > 10_000
        out = os.environ.get("TAMP_SCREENSHOT")
        if out:
            shutil.copy(shot, out)
    finally:
        s.stop()
