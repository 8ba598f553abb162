"""A picture of a scene's HTML file: headless Chromium with no network (every host name resolves to
nothing, every proxied request goes to a closed local port; the page is a local file)."""

from __future__ import annotations

import os
import shutil
import subprocess
import tempfile
from pathlib import Path

from .scene import ViewerError

CHROMIUM_NAMES = ("chromium", "chromium-browser", "google-chrome", "google-chrome-stable")
INSTALL_HINT = ("install Debian's chromium (apt-get install chromium), or set MCDM_PIN_CHROMIUM to a "
                "Chromium or Chrome executable")


def find_chromium() -> str | None:
    """Path of a Chromium/Chrome executable (``MCDM_PIN_CHROMIUM`` first, then ``PATH``), or None."""
    env = os.environ.get("MCDM_PIN_CHROMIUM")
    if env:
        return env if Path(env).is_file() else None
    for name in CHROMIUM_NAMES:
        p = shutil.which(name)
        if p:
            return p
    return None


def chromium_command(html_path, png_path, size=(1000, 800), chromium: str | None = None,
                     user_data_dir: str | None = None) -> list[str]:
    """The headless Chromium command that screenshots ``html_path`` with no network access."""
    exe = chromium or find_chromium()
    if exe is None:
        raise ViewerError(f"no Chromium found for the screenshot: {INSTALL_HINT}")
    return [exe, "--headless", "--no-sandbox", "--disable-gpu", "--disable-background-networking",
            "--disable-component-update", "--disable-sync", "--no-first-run",
            "--disable-default-apps", "--disable-extensions", "--mute-audio", "--hide-scrollbars",
            "--host-resolver-rules=MAP * ~NOTFOUND", "--proxy-server=127.0.0.1:9",
            f"--user-data-dir={user_data_dir}", f"--window-size={size[0]},{size[1]}",
            f"--screenshot={Path(png_path).resolve()}", Path(html_path).resolve().as_uri()]


def screenshot(html_path, png_path, size=(1000, 800), timeout: float = 120.0,
               chromium: str | None = None) -> Path:
    """Render an HTML file in headless Chromium (no network) and write a PNG screenshot."""
    png_path = Path(png_path)
    with tempfile.TemporaryDirectory(prefix="mcdm-pin-chromium-") as profile:
        cmd = chromium_command(html_path, png_path, size, chromium, profile)
        if png_path.exists():
            png_path.unlink()
        try:
            proc = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout,
                                  stdin=subprocess.DEVNULL)
        except subprocess.TimeoutExpired:
            raise ViewerError(f"chromium did not finish the screenshot of {html_path} within "
                              f"{timeout:g} s") from None
    if not png_path.is_file():
        tail = (proc.stderr or "").strip().splitlines()[-3:]
        raise ViewerError(f"chromium wrote no screenshot of {html_path} (exit {proc.returncode}: "
                          f"{' | '.join(tail)})")
    return png_path
