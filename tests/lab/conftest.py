"""The virtual lab in a real headless Chromium (Debian's `chromium`, driven by playwright).

`scripts/setup` installs chromium where it is missing (`scripts/test`: while the tests run,
and these wait for it); without it these tests fail with that instruction (they are never
skipped). Labs run in-process on an ephemeral loopback port, faster than real time; tests
wait on states the page shows, never on wall-clock durations.
Screenshots go to `tmp_path`, or to $PLCLAB_LAB_SHOTS (scripts/lab-screenshots: docs/img).
"""
from __future__ import annotations

import os
import shutil
import time
from pathlib import Path
from typing import Iterator, Optional

import pytest

from plclab.lab import LabThread, open_lab

# where scripts/setup installs chromium in the background (scripts/test: while the tests run)
INSTALL = Path(__file__).resolve().parents[2] / ".venv" / "chromium-install"
INSTALL_WAIT_S = 900


def chromium() -> str:
    """The Chromium the browser tests drive; fails the test with what to do where there is
    none. An install scripts/test started (scripts/setup, PLCLAB_SETUP_CHROMIUM=background) is
    waited for: its status file appears when apt-get is done."""
    found = os.environ.get("PLCLAB_CHROMIUM") or shutil.which("chromium")
    status, log = INSTALL.with_suffix(".status"), INSTALL.with_suffix(".log")
    if not found and log.exists():
        deadline = time.monotonic() + INSTALL_WAIT_S
        while not status.exists() and _installing() and time.monotonic() < deadline:
            time.sleep(0.5)
        found = shutil.which("chromium")
        if not found:
            tail = log.read_text(encoding="utf-8", errors="replace").strip().splitlines()[-3:]
            why = (f"exit status {status.read_text().strip()}" if status.exists()
                   else "stopped before it was done" if not _installing() else f"not done after {INSTALL_WAIT_S} s")
            pytest.fail(f"the lab's browser tests need Debian's chromium: scripts/setup's apt-get install "
                        f"chromium failed ({why}): {' | '.join(tail)}")
    path = found or "/usr/bin/chromium"
    if not Path(path).exists():
        pytest.fail(f"the lab's browser tests need Debian's chromium at {path}: run `bash scripts/setup` "
                    f"as root (it runs apt-get install chromium) or set PLCLAB_CHROMIUM")
    return path


def _installing() -> bool:
    """Whether the background install's process (its pid in INSTALL.pid) still runs."""
    try:
        os.kill(int(INSTALL.with_suffix(".pid").read_text().strip()), 0)
    except (OSError, ValueError):
        return False
    return True


@pytest.fixture(scope="module")
def browser() -> Iterator:
    """One Chromium for the tests of a module (closed after it: playwright's sync API keeps an
    event loop running in this thread, which other tests' asyncio.run must not meet)."""
    from playwright.sync_api import sync_playwright

    path = chromium()
    with sync_playwright() as p:
        b = p.chromium.launch(executable_path=path, args=["--no-sandbox", "--disable-gpu"])
        yield b
        b.close()


@pytest.fixture(scope="module")
def rebinding_browser() -> Iterator:
    """A Chromium that resolves evil.example and attacker.example to 127.0.0.1, as an
    attacker's DNS would (a hostile page, a DNS-rebinding name)."""
    from playwright.sync_api import sync_playwright

    path = chromium()
    with sync_playwright() as p:
        b = p.chromium.launch(executable_path=path, args=[
            "--no-sandbox", "--disable-gpu",
            "--host-resolver-rules=MAP evil.example 127.0.0.1, MAP attacker.example 127.0.0.1"])
        yield b
        b.close()


class LabPage:
    """One running lab and a browser page on it."""

    def __init__(self, browser, stand: str, speed: float, program=None, variant: str = "full",
                 viewport: Optional[dict] = None, mobile: bool = False):
        self.server = open_lab(stand, program=program, variant=variant, port=0, speed=speed, modbus_port=0)
        self.thread = LabThread(self.server)
        self.url = self.thread.start()
        # a phone: its viewport, touch, and 2 screen pixels per CSS pixel
        self.context = browser.new_context(viewport=viewport or {"width": 1400, "height": 1000}, is_mobile=mobile,
                                           has_touch=mobile, device_scale_factor=2 if mobile else 1)
        self.page = self.open()
        self.closed = False

    def open(self):
        page = self.context.new_page()
        page.set_default_timeout(20_000)
        page.goto(self.url)
        page.wait_for_selector("#plc-state[data-state='RUN']")
        return page

    @property
    def lab(self):
        return self.server.lab

    def close(self) -> None:
        if self.closed:            # a test may close its page before the fixture does
            return
        self.closed = True
        self.context.close()
        self.thread.stop()


@pytest.fixture
def lab_page(browser):
    opened: list[LabPage] = []

    def make(stand: str, speed: float = 5.0, **kw) -> LabPage:
        lp = LabPage(browser, stand, speed, **kw)
        opened.append(lp)
        return lp
    yield make
    for lp in opened:
        lp.close()


@pytest.fixture
def shots(tmp_path) -> Path:
    """Where the tests' screenshots go."""
    target = os.environ.get("PLCLAB_LAB_SHOTS")
    path = Path(target) if target else tmp_path
    path.mkdir(parents=True, exist_ok=True)
    return path
