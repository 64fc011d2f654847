"""The live viewer page in a real headless Chromium (Debian's chromium + chromium-driver).

Locally without Chromium the browser test is skipped with the reason; under CI=true it
must run. Nothing is downloaded at test time: the driver and browser paths are explicit.
"""

from __future__ import annotations

import io
import json
import os
import shutil
import socket
import threading
import time

import numpy as np
import pytest
import uvicorn
from fastapi.testclient import TestClient

from app.main import create_app
from app.settings import Settings
from tests.conftest import DATA

CHROMIUM = shutil.which("chromium") or "/usr/bin/chromium"
DRIVER = shutil.which("chromedriver") or "/usr/bin/chromedriver"
HAVE_BROWSER = os.path.exists(CHROMIUM) and os.path.exists(DRIVER)

SESSION = {
    "objects": json.loads((DATA / "thesis_like.json").read_text())["objects"],
    "sensor": {"position_error": 1.0, "normal_error": 0.05},
    "workspace": {"center": [0, 0], "radius": 200},
    "sensor_position": [200, 0],
    "strategy": {"name": "pdm", "budget_ms": 300},
}
TOUCHES = [
    {
        "path": {"origin": [0, -200], "direction": [0, 1], "length": 400},
        "contact": {"point": [5, -40], "normal": [0, -1]},
    },
    {
        "path": {"origin": [200, 0], "direction": [-1, 0], "length": 400},
        "contact": {"point": [50, 0], "normal": [1, 0]},
    },
]


def test_image_json_and_view_page_in_process(tmp_path):
    app = create_app(Settings(db_path=str(tmp_path / "v.db")))
    with TestClient(app) as client:
        sid = client.post("/v1/sessions", json=SESSION).json()["id"]
        empty = client.get(f"/v1/sessions/{sid}/image.json").json()
        assert empty["outlines"] == [] and empty["workspace"]["radius"] == 200
        client.post(f"/v1/sessions/{sid}/observations", json=TOUCHES[0])
        img = client.get(f"/v1/sessions/{sid}/image.json").json()
        hyps = client.get(f"/v1/sessions/{sid}").json()["hypotheses"]
        assert len(img["outlines"]) == len(hyps) > 1
        assert img["drawn"] == img["hypothesis_count"] == len(hyps)
        assert img["blocking"] and all(0 < b["strength"] <= 1 + 1e-9 for b in img["blocking"])
        assert img["observations"][0]["contact"]["normal"] == [0.0, -1.0]
        page = client.get(f"/v1/sessions/{sid}/view")
        assert page.status_code == 200 and page.headers["content-type"].startswith("text/html")
        assert "<script" in page.text and "http" not in page.text.replace("http://www.w3.org", "")
        missing = client.get("/v1/sessions/00000000-0000-4000-8000-000000000000/view")
        assert missing.status_code == 404
        assert missing.headers["content-type"] == "application/problem+json"


@pytest.fixture
def live_server(tmp_path, request):
    key = getattr(request, "param", None)
    app = create_app(Settings(db_path=str(tmp_path / "live.db"), api_key=key))
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    server = uvicorn.Server(uvicorn.Config(app, host="127.0.0.1", port=port, log_level="warning"))
    thread = threading.Thread(target=server.run, daemon=True)
    thread.start()
    deadline = time.monotonic() + 20
    while not server.started and time.monotonic() < deadline:
        time.sleep(0.05)
    assert server.started, "the server did not start"
    yield f"http://127.0.0.1:{port}"
    server.should_exit = True
    thread.join(timeout=10)


@pytest.fixture
def browser(tmp_path):
    if not HAVE_BROWSER:
        if os.environ.get("CI") == "true":
            pytest.fail(
                "CI must run the browser test: install Debian's chromium and chromium-driver"
            )
        pytest.skip(f"no Chromium here ({CHROMIUM}, {DRIVER}); CI installs it")
    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service

    options = webdriver.ChromeOptions()
    options.binary_location = CHROMIUM
    for flag in (
        "--headless=new",
        "--no-sandbox",
        "--disable-gpu",
        "--disable-dev-shm-usage",
        "--disable-quic",
        "--no-first-run",
        "--disable-background-networking",
        "--disable-component-update",
        "--disable-sync",
        "--window-size=1400,900",
        f"--user-data-dir={tmp_path / 'profile'}",
    ):
        options.add_argument(flag)
    driver = webdriver.Chrome(service=Service(executable_path=DRIVER), options=options)
    yield driver
    driver.quit()


def test_viewer_draws_the_image_and_refreshes_in_chromium(live_server, browser, tmp_path):
    import httpx
    from PIL import Image
    from selenium.webdriver.common.by import By
    from selenium.webdriver.support.ui import WebDriverWait

    with httpx.Client(base_url=live_server, timeout=30) as api:
        sid = api.post("/v1/sessions", json=SESSION).json()["id"]
        api.post(f"/v1/sessions/{sid}/observations", json=TOUCHES[0]).raise_for_status()
        state = api.get(f"/v1/sessions/{sid}").json()
        hyps = state["hypotheses"]
        browser.get(f"{live_server}/v1/sessions/{sid}/view")
        wait = WebDriverWait(browser, 60)
        shown = "return document.body.dataset.version"
        wait.until(lambda d: d.execute_script(shown) == str(state["version"]))
        outlines = browser.find_elements(By.CSS_SELECTOR, "#mii path.outline")
        assert len(outlines) == len(hyps)
        assert browser.find_elements(By.CSS_SELECTOR, "#mii .blocking")
        assert browser.find_elements(By.CSS_SELECTOR, "#mii .contact")
        assert browser.find_elements(By.CSS_SELECTOR, "#mii line.path")
        rows = browser.find_elements(By.CSS_SELECTOR, "#hypotheses tbody tr")
        assert len(rows) == len(hyps)
        assert browser.find_element(By.ID, "status").text == "ambiguous"
        # the page ran under its policy (its own script and style allowed by hash) ...
        refused = [e for e in browser.get_log("browser") if "Content Security" in e["message"]]
        assert not refused, refused
        # ... and a script injected into it does not run
        injected = (
            "const s = document.createElement('script'); s.textContent = 'window.pwned = 1';"
            "document.body.appendChild(s); return window.pwned === undefined;"
        )
        assert browser.execute_script(injected)
        shot = Image.open(io.BytesIO(browser.get_screenshot_as_png()))
        pixels = np.asarray(shot.convert("L"), dtype=float)
        assert pixels.std() > 5, "the screenshot is blank"
        shot.save(os.environ.get("VIEWER_SCREENSHOT", tmp_path / "viewer.png"))

        # the page follows the session as it changes
        api.post(f"/v1/sessions/{sid}/observations", json=TOUCHES[1]).raise_for_status()
        state = api.get(f"/v1/sessions/{sid}").json()
        wait.until(lambda d: d.execute_script(shown) == str(state["version"]))
        after = state["hypotheses"]
        assert len(browser.find_elements(By.CSS_SELECTOR, "#hypotheses tbody tr")) == len(after)


@pytest.mark.parametrize("live_server", ["s3cret"], indirect=True)
def test_with_a_key_the_viewer_opens_through_its_link_in_chromium(live_server, browser):
    import httpx
    from selenium.webdriver.common.by import By
    from selenium.webdriver.support.ui import WebDriverWait

    key = {"Authorization": "Bearer s3cret"}
    with httpx.Client(base_url=live_server, timeout=30, headers=key) as api:
        sid = api.post("/v1/sessions", json=SESSION).json()["id"]
        api.post(f"/v1/sessions/{sid}/observations", json=TOUCHES[0]).raise_for_status()
        state = api.get(f"/v1/sessions/{sid}").json()
        link = api.post(f"/v1/sessions/{sid}/view-link").json()
    browser.get(live_server + link["url"])
    WebDriverWait(browser, 60).until(
        lambda d: d.execute_script("return document.body.dataset.version") == str(state["version"])
    )
    assert len(browser.find_elements(By.CSS_SELECTOR, "#mii path.outline")) == len(
        state["hypotheses"]
    )
    # without the token the page itself is refused
    browser.get(f"{live_server}/v1/sessions/{sid}/view")
    assert "Unauthorized" in browser.page_source
