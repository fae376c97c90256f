#!/usr/bin/python3
"""The scheduler's dashboard in a real browser: Debian's chromium, driven by Selenium
(python3-selenium) through chromium-driver, headless.

  dashboard_check.py --url http://127.0.0.1:PORT --token TOKEN --job RENDERING_JOB --cancel JOB \\
      --workers 2 --screenshot FILE.png [--animation PAUSED_ANIMATION]

Logs in with the token, then checks what a person would look at: the jobs page lists the
rendering job and its progress increases without a reload; the job page's image changes while it
renders (its pixels, read back from the page); the cancel button cancels the other job; the
workers page shows every worker up. Saves a screenshot of the job page while it renders. With
--animation, resumes it, opens its page while its frames merge, and wants every thumbnail loaded.
job_page_paints() is how tools/measure_dashboard.py times the job page's first paint.

Prints one JSON line of what it saw; exit 0 only when every check held.
"""
import argparse
import hashlib
import json
import statistics
import sys
import time
import urllib.parse

from selenium import webdriver
from selenium.webdriver.chrome.service import Service
from selenium.webdriver.common.by import By

WAIT = 120  # seconds any one thing may take to appear


def browser():
    options = webdriver.ChromeOptions()
    options.binary_location = "/usr/bin/chromium"
    for flag in ("--headless=new", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage",
                 "--window-size=1280,900"):  # a laptop's width: the tables must fit it (issue #32)
        options.add_argument(flag)
    return webdriver.Chrome(service=Service("/usr/bin/chromedriver"), options=options)


def wait_for(what, check, timeout=WAIT, every=0.1):
    """check() until it returns something truthy; that value, or an AssertionError naming `what`."""
    until = time.monotonic() + timeout
    while time.monotonic() < until:
        try:
            value = check()
            if value:
                return value
        except Exception:  # an element not there yet, a page between loads
            pass
        time.sleep(every)
    raise AssertionError(f"timed out waiting for {what}")


def text_of(driver, selector):
    """The text of the element `selector` picks, read in one step: the pages redraw rows and facts
    as events arrive, so an element found earlier may be gone by the time it is read."""
    return driver.execute_script("const e = document.querySelector(arguments[0]); return e ? e.textContent : null;",
                                 selector)


def click(driver, selector):
    """Finds and clicks in one step of the page (an element found earlier may have been redrawn);
    false while there is no such element or it is disabled (a click on it would do nothing)."""
    return driver.execute_script("const e = document.querySelector(arguments[0]); if (!e || e.disabled) return false; "
                                 "e.click(); return true;", selector)


def overflow(driver):
    """How many CSS pixels the page is wider than the window (0: it fits, no sideways scrolling)."""
    return driver.execute_script("return Math.max(0, document.documentElement.scrollWidth - window.innerWidth);")


def units_done(text):
    """'3/16 tiles' or '1/4 frames, 30/64 units' -> the units done."""
    return int(text.split(",")[-1].strip().split("/")[0])


def image_digest(driver):
    """The SHA-256 of the live image's pixels as the page shows them (drawn into a canvas)."""
    data = driver.execute_script("""
        const img = document.getElementById('live');
        if (!img.complete || img.naturalWidth === 0) return null;
        const c = document.createElement('canvas');
        c.width = img.naturalWidth; c.height = img.naturalHeight;
        const g = c.getContext('2d');
        g.drawImage(img, 0, 0);
        return Array.from(g.getImageData(0, 0, c.width, c.height).data).join(',');""")
    return hashlib.sha256(data.encode()).hexdigest() if data else None


def run(args, driver, seen):
    # Logged in from a link whose `next` leads elsewhere ("/\host" is "//host" to a browser): the
    # login stays on the dashboard, on its jobs page.
    driver.get(args.url + "/login.html?next=" + urllib.parse.quote("/\\elsewhere.invalid/"))
    driver.find_element(By.ID, "token").send_keys(args.token)
    driver.find_element(By.CSS_SELECTOR, "#login button").click()
    landed = wait_for("a page after logging in", lambda: (lambda u: u if "/login.html" not in u else None)(
        driver.current_url))
    assert landed.startswith(args.url + "/"), f"the login led off the dashboard, to {landed}"
    wait_for("the jobs page after logging in", lambda: text_of(driver, f"#job-{args.job} td.state"))

    # Progress grows on the page without a reload: a marker set now must still be there.
    driver.execute_script("window.farmNoReload = true;")
    cell = f"#job-{args.job} td.progress span"
    first = units_done(wait_for("the job's progress", lambda: text_of(driver, cell)))
    later = wait_for("the job's progress to increase",
                     lambda: (lambda n: n if n > first else None)(units_done(text_of(driver, cell))))
    assert driver.execute_script("return window.farmNoReload === true;"), "the jobs page reloaded"
    seen["progress"] = [first, later]
    seen["jobs_overflow_px"] = overflow(driver)
    assert seen["jobs_overflow_px"] == 0, f"the jobs page is {seen['jobs_overflow_px']} px wider than 1280"

    # The job page: its image changes while the job renders.
    driver.get(f"{args.url}/job.html?id={args.job}")
    digest = wait_for("the live image", lambda: image_digest(driver))
    changed = wait_for("the live image to change",
                       lambda: (lambda d: d if d and d != digest else None)(image_digest(driver)))
    state = text_of(driver, "#facts dd.state")
    driver.save_screenshot(args.screenshot)
    seen["image_changed"] = digest != changed
    seen["state_at_screenshot"] = state
    seen["log_rows"] = len(driver.find_elements(By.CSS_SELECTOR, "#log tbody tr"))
    assert state == "running", f"the job was {state} when its page was captured"

    # The cancel button, on the jobs page.
    driver.get(args.url + "/")
    wait_for("the cancel button", lambda: click(driver, f"#job-{args.cancel} button.cancel"))
    seen["cancelled"] = wait_for("the job to show cancelled",
                                 lambda: text_of(driver, f"#job-{args.cancel} td.state") == "cancelled")

    # The workers page: every worker, up.
    driver.get(args.url + "/workers.html")
    seen["workers_up"] = wait_for(f"{args.workers} workers up", lambda: (lambda n: n if n == args.workers else None)(
        driver.execute_script("return [...document.querySelectorAll('#workers tbody td.state')]"
                              ".filter(td => td.textContent === 'up').length;")))
    seen["workers_overflow_px"] = overflow(driver)
    assert seen["workers_overflow_px"] == 0, f"the workers page is {seen['workers_overflow_px']} px wider than 1280"

    if args.animation:
        animation(args, driver, seen)


def job_page_paints(driver, url, job_id, runs):
    """The job's page loaded `runs` times: the median and worst first contentful paint, and time
    until the job's facts are shown (performance mark `farm-job-shown`), in ms."""
    paints, shown = [], []
    for _ in range(runs):
        driver.get(f"{url}/job.html?id={job_id}")
        wait_for("the measured job's facts", lambda: driver.execute_script(
            "return performance.getEntriesByName('farm-job-shown').length > 0"))
        paints.append(driver.execute_script(
            "const p = performance.getEntriesByName('first-contentful-paint'); return p.length ? p[0].startTime : null;"))
        shown.append(driver.execute_script("return performance.getEntriesByName('farm-job-shown')[0].startTime;"))
    return {"first_contentful_paint_ms": {"median": statistics.median(paints), "max": max(paints)},
            "job_facts_shown_ms": {"median": statistics.median(shown), "max": max(shown)}}


# Installed in the animation's job page before its own scripts: the replies to the page's GetJob
# calls after its first are held until window.farmRereads.release(), which returns how many it let go.
# The test's own calls (its `api`, evaluated with a second argument) pass straight through.
HOLD_REREADS = """
(() => {
  const fetchNow = window.fetch.bind(window);
  const held = [];
  let jobReads = 0;
  window.farmRereads = { release: () => { const n = held.length; for (const go of held.splice(0)) go(); return n; } };
  window.fetch = (path, init) => {
    const reply = fetchNow(path, init);
    const getJob = /^\\/api\\/v1\\/jobs\\/[^/?]+$/.test(String(path)) && !(init && init.farmProbe);
    if (!getJob || ++jobReads === 1) return reply;
    return reply.then((r) => r.text().then((body) => new Promise((go) => held.push(
      () => go(new Response(body, { status: r.status, statusText: r.statusText, headers: r.headers }))))));
  };
})();
"""


def animation(args, driver, seen):
    """The paused animation resumed; its job page opened once a frame is merged and before the last
    is; once it succeeded, every frame's thumbnail must have loaded."""
    job = f"/api/v1/jobs/{args.animation}"
    api = "return fetch(arguments[0], {...arguments[1], farmProbe: true}).then(r => r.ok ? r.json() : null);"
    resumed = driver.execute_script(api, job + "/resume", {
        "method": "POST", "headers": {"Content-Type": "application/json"}, "body": "{}"})
    assert resumed, "the animation could not be resumed"
    frames = resumed["frames_total"]
    done = wait_for("the animation's first frame", lambda: (lambda j: j if j and j["frames_done"] > 0 else None)(
        driver.execute_script(api, job, {})), every=0.02)
    seen["animation_frames_done_at_open"] = done["frames_done"]
    driver.execute_cdp_cmd("Page.addScriptToEvaluateOnNewDocument", {"source": HOLD_REREADS})
    driver.get(f"{args.url}/job.html?id={args.animation}")
    # While it renders, every download link is of a merged frame: each one is there to fetch.
    wait_for("the first download links", lambda: driver.find_elements(By.CSS_SELECTOR, "#downloads a"))
    links = driver.execute_script("return [...document.querySelectorAll('#downloads a')].map(a => a.href)"
                                  ".filter(h => h.includes('frame='));")
    statuses = driver.execute_script("return Promise.all(arguments[0].map(h => fetch(h).then(r => r.status)));", links)
    seen["animation_links_at_open"] = len(links)
    broken = [h for h, s in zip(links, statuses) if s != 200]
    assert not broken, f"links to frames not merged: {broken[:4]} ({len(broken)} of {len(links)})"
    # The page's rereads of the job (on the stream's opening, on `updated`) come back only once the
    # page shows the success its events brought: the state they read earlier must not replace it.
    wait_for("the animation to succeed on the scheduler",
             lambda: (lambda j: j and j["state"] == "JOB_STATE_SUCCEEDED")(driver.execute_script(api, job, {})))
    try:
        wait_for("the animation's page to show its success", lambda: text_of(driver, "#facts dd.state") == "succeeded",
                 timeout=30)
        seen["animation_rereads_held"] = driver.execute_script("return window.farmRereads.release();")
        time.sleep(1)  # the released replies are read and applied within a few tasks
    except AssertionError:  # it succeeded before the stream opened: only a reread can tell the page
        seen["animation_rereads_held"] = -driver.execute_script("return window.farmRereads.release();")
    wait_for("the animation to show succeeded", lambda: text_of(driver, "#facts dd.state") == "succeeded", timeout=5)
    loaded = "return [...document.querySelectorAll('#thumbs img')].filter(i => i.complete && i.naturalWidth > 0).length"
    try:
        seen["animation_thumbnails"] = wait_for(f"{frames} thumbnails", lambda: (lambda n: n if n == frames else None)(
            driver.execute_script(loaded)), timeout=30)
    except AssertionError:
        seen["animation_thumbnails"] = driver.execute_script(loaded)
        raise AssertionError(f"{seen['animation_thumbnails']} of the animation's {frames} thumbnails loaded")


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--url", required=True)
    parser.add_argument("--token", required=True)
    parser.add_argument("--job", required=True, help="a job that renders for a while")
    parser.add_argument("--cancel", required=True, help="an active job for the cancel button")
    parser.add_argument("--animation", help="a paused animation, resumed here and watched as its frames merge")
    parser.add_argument("--workers", type=int, required=True)
    parser.add_argument("--screenshot", required=True)
    args = parser.parse_args()
    seen = {}
    driver = browser()
    try:
        run(args, driver, seen)
        seen["ok"] = True
    except AssertionError as e:
        seen["ok"] = False
        seen["problem"] = str(e)
    finally:
        driver.quit()
    print(json.dumps(seen))
    return 0 if seen["ok"] else 1


if __name__ == "__main__":
    sys.exit(main())
