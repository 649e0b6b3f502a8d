"""A headless Chromium driven over the DevTools protocol, for the viewer's tests and measurements.

The protocol runs over a pipe (``--remote-debugging-pipe``: JSON messages ended by a NUL byte on the child's
file descriptors 3 and 4), so no websocket library and no port are needed. WebGL2 renders on the CPU through
SwiftShader (``--use-angle=swiftshader``), so this works on a machine without a GPU.

Examples
--------
>>> with Browser() as browser:                                          # doctest: +SKIP
...     page = browser.open("file:///tmp/gold.html?env=0", size=(900, 700))
...     page.wait("window.frenbrdfView.ready || window.frenbrdfView.error")
...     png = page.screenshot((16, 60, 256, 256))
"""

from __future__ import annotations

import base64
import fcntl
import json
import os
import shutil
import subprocess
import tempfile
import time

#: The names Chromium goes by (Debian's package installs ``chromium``).
CANDIDATES = ("chromium", "chromium-browser", "google-chrome", "google-chrome-stable", "chrome")


def find_chromium() -> str | None:
    """The Chromium executable on the PATH (or ``$FRENBRDF_CHROMIUM``), or None."""
    given = os.environ.get("FRENBRDF_CHROMIUM")
    if given:
        return given
    return next((path for path in map(shutil.which, CANDIDATES) if path), None)


class BrowserError(RuntimeError):
    """Chromium did not start, answer, or reach a state in time."""


class Browser:
    """One headless Chromium process (a context manager); :meth:`open` loads a page in a new tab."""

    def __init__(self, executable: str | None = None, timeout: float = 60.0):
        executable = executable or find_chromium()
        if executable is None:
            raise BrowserError(f"no Chromium found (looked for {', '.join(CANDIDATES)}; apt-get install chromium)")
        self.timeout = timeout
        self._profile = tempfile.TemporaryDirectory(prefix="frenbrdf-chromium-")
        to_child, self._write = os.pipe()
        self._read, from_child = os.pipe()

        def descriptors():  # the child reads commands on fd 3 and writes answers on fd 4
            # Moved above 4 first, so that placing one cannot close the other; dup2's copies are inheritable.
            high = [fcntl.fcntl(fd, fcntl.F_DUPFD, 10) for fd in (to_child, from_child)]
            os.dup2(high[0], 3)
            os.dup2(high[1], 4)

        arguments = [executable, "--headless", "--no-sandbox", "--remote-debugging-pipe", "--use-angle=swiftshader",
                     "--enable-unsafe-swiftshader", "--ignore-gpu-blocklist", "--no-first-run",
                     "--no-default-browser-check", "--disable-extensions", "--disable-background-networking",
                     "--disable-component-update", "--disable-sync", "--force-device-scale-factor=1",
                     "--hide-scrollbars", f"--user-data-dir={self._profile.name}", "about:blank"]
        # close_fds=False: fds 3 and 4, made in the child, must survive; the parent's own are close-on-exec.
        self.process = subprocess.Popen(arguments, close_fds=False, preexec_fn=descriptors,
                                        stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
                                        stderr=subprocess.DEVNULL)
        os.close(to_child)
        os.close(from_child)
        self._buffer = b""
        self._next_id = 0
        #: The events received so far (messages that answer no command), in order.
        self.events: list[dict] = []

    def __enter__(self) -> Browser:
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def close(self) -> None:
        if self.process.poll() is None:
            try:
                self.send("Browser.close", timeout=5)
            except (BrowserError, OSError):
                pass
            try:
                self.process.wait(5)
            except subprocess.TimeoutExpired:
                self.process.kill()
                self.process.wait()
        for fd in (self._read, self._write):
            try:
                os.close(fd)
            except OSError:
                pass
        self._profile.cleanup()

    def _message(self, deadline: float) -> dict:
        import select

        while b"\0" not in self._buffer:
            left = deadline - time.monotonic()
            if left <= 0 or not select.select([self._read], [], [], left)[0]:
                raise BrowserError("Chromium did not answer in time")
            chunk = os.read(self._read, 1 << 20)
            if not chunk:
                raise BrowserError("Chromium closed the DevTools pipe (it exited)")
            self._buffer += chunk
        message, self._buffer = self._buffer.split(b"\0", 1)
        return json.loads(message)

    def send(self, method: str, params: dict | None = None, session: str | None = None,
             timeout: float | None = None) -> dict:
        """Sends a command and returns its result; events that arrive meanwhile are kept in :attr:`events`."""
        self._next_id += 1
        message = {"id": self._next_id, "method": method, "params": params or {}}
        if session:
            message["sessionId"] = session
        os.write(self._write, json.dumps(message).encode() + b"\0")
        deadline = time.monotonic() + (self.timeout if timeout is None else timeout)
        while True:
            answer = self._message(deadline)
            if answer.get("id") == self._next_id:
                if "error" in answer:
                    raise BrowserError(f"{method}: {answer['error'].get('message')}")
                return answer.get("result", {})
            self.events.append(answer)

    def open(self, url: str, size: tuple[int, int] = (1000, 800)) -> Page:
        """A new tab of ``size`` pixels at ``url``, with its console, errors and network requests recorded."""
        target = self.send("Target.createTarget", {"url": "about:blank"})["targetId"]
        session = self.send("Target.attachToTarget", {"targetId": target, "flatten": True})["sessionId"]
        page = Page(self, session)
        for domain in ("Page", "Runtime", "Network", "Log"):
            page.send(f"{domain}.enable")
        page.send("Emulation.setDeviceMetricsOverride", {"width": size[0], "height": size[1], "deviceScaleFactor": 1,
                                                         "mobile": False})
        page.send("Page.navigate", {"url": url})
        return page


class Page:
    """A tab of a :class:`Browser`."""

    def __init__(self, browser: Browser, session: str):
        self.browser, self.session = browser, session

    def send(self, method: str, params: dict | None = None) -> dict:
        return self.browser.send(method, params, self.session)

    def evaluate(self, expression: str):
        """The value of a JavaScript expression (awaited if a promise), as JSON."""
        result = self.send("Runtime.evaluate", {"expression": expression, "returnByValue": True,
                                                "awaitPromise": True})
        if "exceptionDetails" in result:
            raise BrowserError(f"{expression}: {result['exceptionDetails'].get('text')} "
                               f"{result['exceptionDetails'].get('exception', {}).get('description', '')}")
        return result["result"].get("value")

    def wait(self, expression: str, timeout: float = 60.0, interval: float = 0.1):
        """Polls until ``expression`` is truthy and returns its value."""
        deadline = time.monotonic() + timeout
        while True:
            try:
                value = self.evaluate(expression)
            except BrowserError:  # the page is still loading
                value = None
            if value:
                return value
            if time.monotonic() > deadline:
                raise BrowserError(f"the page did not reach {expression!r} within {timeout:g} s")
            time.sleep(interval)

    def screenshot(self, clip: tuple[float, float, float, float] | None = None) -> bytes:
        """A PNG of the viewport, or of ``clip`` = (x, y, width, height) in CSS pixels."""
        params: dict[str, object] = {"format": "png"}
        if clip:
            params["clip"] = dict(zip(("x", "y", "width", "height"), clip, strict=True), scale=1)
        return base64.b64decode(self.send("Page.captureScreenshot", params)["data"])

    def events(self, *methods: str) -> list[dict]:
        """The events of this tab recorded so far, of the given methods."""
        return [e for e in self.browser.events if e.get("sessionId") == self.session and e.get("method") in methods]

    def console_errors(self) -> list[str]:
        """Console errors, uncaught exceptions and error log entries of this tab."""
        errors = []
        for event in self.events("Runtime.consoleAPICalled", "Runtime.exceptionThrown", "Log.entryAdded"):
            params = event["params"]
            if event["method"] == "Runtime.consoleAPICalled" and params.get("type") in ("error", "assert"):
                errors.append(" ".join(str(a.get("value", a.get("description"))) for a in params.get("args", [])))
            elif event["method"] == "Runtime.exceptionThrown":
                errors.append(params["exceptionDetails"].get("text", "exception"))
            elif event["method"] == "Log.entryAdded" and params["entry"].get("level") == "error":
                errors.append(params["entry"].get("text", ""))
        return errors

    def requests(self) -> list[str]:
        """The URLs this tab requested."""
        return [e["params"]["request"]["url"] for e in self.events("Network.requestWillBeSent")]
