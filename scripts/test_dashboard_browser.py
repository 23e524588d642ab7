#!/usr/bin/python3
"""Renders the dashboard in headless Chromium and checks that every plot loads.

A copy of the page gets a script that, once the page has loaded, writes into the DOM how many
images there are and which have decoded (naturalWidth > 0); Chromium's --dump-dom prints the
DOM after the load and we read that record back. The page must also be self-contained: no
resource is fetched from the network. Needs Debian's chromium (scripts/install-deps.sh --browser;
`make test-browser` runs that first).

  scripts/test_dashboard_browser.py results/dashboard/index.html [--screenshot shot.png]
"""
import argparse
import html
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile

PROBE = """<script>
window.addEventListener("load", function () {
  var imgs = Array.prototype.slice.call(document.images), failed = [];
  imgs.forEach(function (im, i) { if (!(im.complete && im.naturalWidth > 0)) failed.push(im.alt || String(i)); });
  var pre = document.createElement("pre");
  pre.id = "cdp-browser-check";
  pre.textContent = JSON.stringify({images: imgs.length, failed: failed});
  document.body.appendChild(pre);
});
</script>"""
RESULT = re.compile(r'<pre id="cdp-browser-check">(.*?)</pre>', re.S)
# src/href/url() pointing anywhere but an embedded data: URI or an in-page anchor.
EXTERNAL = re.compile(r'''(?:\bsrc|\bhref)\s*=\s*["'](?!data:|#)([^"']+)|url\(\s*["']?(?!data:)([^"')]+)''', re.I)
# A link to a page beside this one (the mesh viewer) is followed only when clicked: it loads nothing.
RELATIVE_LINK = re.compile(r'''<a\b[^>]*?\bhref\s*=\s*["'](?![a-z][a-z0-9+.-]*:|//)[^"']*["']''', re.I)


def chromium():
    for name in ("chromium", "chromium-browser", "google-chrome"):
        path = shutil.which(name)
        if path:
            return path
    return None


def run(browser, args, timeout=180):
    # --no-sandbox: CI containers run as root, where Chromium's sandbox refuses to start.
    base = [browser, "--headless", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage", "--no-first-run",
            "--disable-extensions", "--disable-background-networking", "--virtual-time-budget=10000"]
    return subprocess.run(base + args, capture_output=True, text=True, timeout=timeout)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("page")
    ap.add_argument("--screenshot", help="also save a screenshot of the page here")
    a = ap.parse_args()
    try:
        with open(a.page, encoding="utf-8") as f:
            text = f.read()
    except OSError as e:
        sys.exit("test_dashboard_browser: {}".format(e))
    external = [m.group(1) or m.group(2) for m in EXTERNAL.finditer(RELATIVE_LINK.sub("<a", text))]
    if external:
        sys.exit("test_dashboard_browser: FAIL: {} loads external resources: {}".format(a.page, ", ".join(external[:5])))
    expected = len(re.findall(r"<img\b", text))
    browser = chromium()
    if browser is None:
        sys.exit("test_dashboard_browser: no chromium on PATH; install it with: bash scripts/install-deps.sh --browser")
    with tempfile.TemporaryDirectory() as tmp:
        probe_page = os.path.join(tmp, "page.html")
        with open(probe_page, "w", encoding="utf-8") as f:
            f.write(text.replace("</body>", PROBE + "</body>") if "</body>" in text else text + PROBE)
        profile = ["--user-data-dir=" + os.path.join(tmp, "profile")]
        try:
            r = run(browser, profile + ["--dump-dom", "file://" + probe_page])
        except subprocess.TimeoutExpired:
            sys.exit("test_dashboard_browser: FAIL: chromium did not finish within 180 s")
        m = RESULT.search(r.stdout)
        if r.returncode != 0 or not m:
            sys.exit("test_dashboard_browser: FAIL: chromium (exit {}) did not report on the page's images; "
                     "its stderr ends:\n{}".format(r.returncode, r.stderr[-2000:]))
        result = json.loads(html.unescape(m.group(1)))
        if a.screenshot:
            shot = os.path.abspath(a.screenshot)
            run(browser, profile + ["--window-size=1400,3000", "--screenshot=" + shot, "file://" + os.path.abspath(a.page)])
            if not os.path.exists(shot):
                print("test_dashboard_browser: warning: no screenshot written", file=sys.stderr)
    problems = []
    if result["images"] != expected:
        problems.append("the browser saw {} images, the page has {}".format(result["images"], expected))
    if result["failed"]:
        problems.append("{} of {} images did not load: {}".format(len(result["failed"]), result["images"],
                                                                   ", ".join(result["failed"][:10])))
    if expected == 0:
        problems.append("the page has no plots (no benchmark runs recorded?)")
    if problems:
        sys.exit("test_dashboard_browser: FAIL: {}: {}".format(a.page, "; ".join(problems)))
    print("test_dashboard_browser: ok: all {} plots of {} load in {}".format(result["images"], a.page,
                                                                            os.path.basename(browser)))


if __name__ == "__main__":
    main()
