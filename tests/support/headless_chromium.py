"""A real browser for tests: Debian's headless Chromium driven over the DevTools protocol
through a pipe (--remote-debugging-pipe: JSON messages ending in a NUL byte, read by Chromium
on fd 3 and written on fd 4), with nothing but the standard library.

    with Chromium() as browser:
        page = browser.open("file:///tmp/x/index.html")
        value = browser.evaluate(page, "new Promise(r => ...)")  # awaited, returned by value
        errors = browser.console_errors(page)

Chromium() raises Unavailable when no chromium is installed, so a test can skip.
"""
import json
import os
import shutil
import subprocess
import tempfile


class Unavailable(RuntimeError):
    pass


class Chromium:
    def __init__(self, timeout=60.0, file_access=True):
        """file_access=False leaves out --allow-file-access-from-files: file:// pages may then not
        fetch other files, as when a user double-clicks a page."""
        exe = shutil.which("chromium") or shutil.which("chromium-browser")
        if exe is None:
            raise Unavailable("chromium is not installed (Debian: apt-get install chromium)")
        self._profile = tempfile.TemporaryDirectory()
        to_browser_r, self._to_browser = os.pipe()
        self._from_browser, from_browser_w = os.pipe()
        # fds 3 and 4 in the child are the protocol's pipes (moved out of the way first: the
        # pipes themselves may have got numbers 3 or 4)
        def child_fds():
            import fcntl
            high_r = fcntl.fcntl(to_browser_r, fcntl.F_DUPFD, 10)
            high_w = fcntl.fcntl(from_browser_w, fcntl.F_DUPFD, 10)
            os.dup2(high_r, 3)
            os.dup2(high_w, 4)
        self._process = subprocess.Popen(
            [exe, "--headless=new", "--no-sandbox", "--disable-gpu", "--remote-debugging-pipe"] +
            (["--allow-file-access-from-files"] if file_access else []) +
            ["--autoplay-policy=no-user-gesture-required",
             "--user-data-dir=" + self._profile.name, "--no-first-run", "about:blank"],
            stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
            pass_fds=(3, 4, to_browser_r, from_browser_w), preexec_fn=child_fds)
        os.close(to_browser_r)
        os.close(from_browser_w)
        self._buffer = b""
        self._next_id = 0
        self._events = []
        self._timeout = timeout

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def close(self):
        if self._process.poll() is None:
            try:
                self._send("Browser.close")
            except (OSError, RuntimeError):
                pass
            try:
                self._process.wait(10)
            except subprocess.TimeoutExpired:
                self._process.kill()
                self._process.wait()
        for fd in (self._to_browser, self._from_browser):
            try:
                os.close(fd)
            except OSError:
                pass
        self._profile.cleanup()

    def _read_message(self):
        import select
        while b"\0" not in self._buffer:
            ready, _, _ = select.select([self._from_browser], [], [], self._timeout)
            if not ready:
                raise RuntimeError(f"chromium said nothing for {self._timeout} s")
            chunk = os.read(self._from_browser, 1 << 16)
            if not chunk:
                raise RuntimeError("chromium closed its pipe (it exited)")
            self._buffer += chunk
        message, self._buffer = self._buffer.split(b"\0", 1)
        return json.loads(message)

    def _send(self, method, params=None, session=None):
        self._next_id += 1
        message = {"id": self._next_id, "method": method, "params": params or {}}
        if session:
            message["sessionId"] = session
        os.write(self._to_browser, json.dumps(message).encode() + b"\0")
        while True:
            reply = self._read_message()
            if reply.get("id") == self._next_id:
                if "error" in reply:
                    raise RuntimeError(f"{method}: {reply['error']}")
                return reply.get("result", {})
            self._events.append(reply)

    def open(self, url):
        """A new tab at `url`, loaded; returns its session."""
        target = self._send("Target.createTarget", {"url": "about:blank"})["targetId"]
        session = self._send("Target.attachToTarget", {"targetId": target, "flatten": True})["sessionId"]
        for domain in ("Page", "Runtime", "Log"):
            self._send(domain + ".enable", session=session)
        self._send("Page.navigate", {"url": url}, session)
        while not any(e.get("method") == "Page.loadEventFired" and e.get("sessionId") == session for e in self._events):
            self._events.append(self._read_message())
        return session

    def evaluate(self, session, expression):
        """The value of a JavaScript expression (a promise is awaited); raises on a JS exception."""
        result = self._send("Runtime.evaluate", {"expression": expression, "awaitPromise": True, "returnByValue": True},
                            session)
        if "exceptionDetails" in result:
            raise RuntimeError("javascript: " + json.dumps(result["exceptionDetails"])[:500])
        return result["result"].get("value")

    def set_viewport(self, session, width, height):
        """The page's size in CSS pixels, one device pixel each (screenshots are width x height)."""
        self._send("Emulation.setDeviceMetricsOverride",
                   {"width": width, "height": height, "deviceScaleFactor": 1, "mobile": False}, session)

    def screenshot(self, session, path):
        import base64
        data = self._send("Page.captureScreenshot", {"format": "png"}, session)["data"]
        with open(path, "wb") as f:
            f.write(base64.b64decode(data))

    def console_errors(self, session):
        """Console errors, uncaught exceptions and failed loads the page reported so far."""
        errors = []
        for e in self._events:
            if e.get("sessionId") != session:
                continue
            p = e.get("params", {})
            if e.get("method") == "Runtime.exceptionThrown":
                errors.append(p["exceptionDetails"].get("text", "") + " " +
                              str(p["exceptionDetails"].get("exception", {}).get("description", "")))
            elif e.get("method") == "Runtime.consoleAPICalled" and p.get("type") == "error":
                errors.append(" ".join(str(a.get("value", a.get("description", ""))) for a in p.get("args", [])))
            elif e.get("method") == "Log.entryAdded" and p["entry"].get("level") == "error":
                errors.append(p["entry"].get("text", "") + " " + p["entry"].get("url", ""))
        return errors
