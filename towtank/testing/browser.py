"""Headless Chromium for the live page's tests and benchmark (selenium, Debian's chromium).

The browser may reach 127.0.0.1 and nothing else: every other host name resolves to nothing
and every request that escapes that rule goes to a closed proxy port, so a page that needed the
internet (a CDN script, a web font) fails visibly instead of loading.
"""

from __future__ import annotations

import os
import socket
from pathlib import Path
from typing import Any

CHROMIUM = "/usr/bin/chromium"
CHROMEDRIVER = "/usr/bin/chromedriver"


def free_port() -> int:
    """A TCP port on 127.0.0.1 that nothing listens on now."""
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return int(sock.getsockname()[1])


def browser_missing() -> str | None:
    """Why the browser cannot be started here (one sentence), or None when it can."""
    try:
        import selenium  # noqa: F401  (loaded on use: only browser tests need selenium)
    except ImportError:
        return "selenium is not installed (pip install '.[test]')"
    for path, what in ((CHROMIUM, "chromium"), (CHROMEDRIVER, "chromedriver")):
        if not os.access(path, os.X_OK):
            return f"{path} is absent (apt-get install chromium chromium-driver for {what})"
    return None


def start_chromium(profile: Path) -> Any:
    """A headless Chromium driven by selenium, its profile in ``profile``, loopback only."""
    from selenium import webdriver  # loaded on use: only browser tests need selenium
    from selenium.webdriver.chrome.service import Service

    closed = free_port()  # nothing listens there: any request that escapes the rules fails
    opts = webdriver.ChromeOptions()
    opts.binary_location = CHROMIUM
    for arg in ("--headless=new", "--no-sandbox", "--disable-gpu",
                "--disable-background-networking", "--disable-component-update",
                "--disable-sync", "--no-first-run", "--disable-dev-shm-usage",
                f"--user-data-dir={profile}",
                "--host-resolver-rules=MAP * ~NOTFOUND, EXCLUDE 127.0.0.1",
                f"--proxy-server=http://127.0.0.1:{closed}",
                "--proxy-bypass-list=127.0.0.1", "--window-size=1600,1900",
                "--force-device-scale-factor=1", "--lang=en-GB"):
        opts.add_argument(arg)
    driver = webdriver.Chrome(service=Service(CHROMEDRIVER), options=opts)
    driver.set_page_load_timeout(20)
    return driver
