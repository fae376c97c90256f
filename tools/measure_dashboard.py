#!/usr/bin/python3
"""Measures the dashboard's two targets of issue #19 on a real farm (numbers, not a test):

 1. What watching a job live costs the job: the same path-traced job rendered in turn with
    nobody watching, with a client that does what the job page does (the job's event stream read
    to the end, and its live image fetched every 300 ms as the page refreshes it), and with
    headless chromium on the job page itself, --rounds times each; prints the median
    render_seconds of each and the ratios to the unwatched one. The worker is pinned to CPU 0, the
    scheduler, the client and the browser to CPU 1: on a farm the browser runs on the viewer's
    machine, so the first ratio is the dashboard's own cost on the scheduler, while the second
    adds a browser drawing on the scheduler's only core.
 2. The job page's first paint with --jobs jobs in the store: that many small jobs are submitted
    first, then the page is loaded --paints times; prints the median and worst
    first-contentful-paint and the time until the job's facts are shown.

  /usr/bin/python3 tools/measure_dashboard.py --farm build/release/server/farm [--rounds 3] [--jobs 1000]

Needs chromium, chromium-driver and python3-selenium (deploy/install-deps.sh).
"""
import argparse
import json
import os
import threading
import urllib.error
import urllib.request
import re
import statistics
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
JOBS = os.path.join(HERE, os.pardir, "jobs")
sys.path.insert(0, os.path.join(HERE, os.pardir, "tests", "browser"))
import dashboard_check  # noqa: E402  (the browser the dashboard test drives)


def start(command, pattern, cpu=None):
    """Starts `command` (on CPU `cpu`) and reads its output until `pattern`; (process, output)."""
    if cpu is not None:
        command = ["taskset", "-c", str(cpu)] + command
    process = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    seen = ""
    until = time.monotonic() + 60
    while time.monotonic() < until:
        seen += process.stdout.readline()
        if re.search(pattern, seen):
            return process, seen
    raise SystemExit(f"{command} did not start:\n{seen}")


def run(farm, *args):
    return subprocess.run([farm, *args], check=True, capture_output=True, text=True).stdout


def submit(farm, scheduler, job, *overrides):
    return run(farm, "submit", job, "--scheduler", scheduler, *overrides).strip().split()[-1]


def wait_done(farm, scheduler, job_id):
    while True:
        job = json.loads(run(farm, "status", job_id, "--json", "--scheduler", scheduler))
        if job["state"] in ("JOB_STATE_SUCCEEDED", "JOB_STATE_FAILED", "JOB_STATE_CANCELLED"):
            return job
        time.sleep(0.1)


def browser():
    driver = dashboard_check.browser()
    # The browser shares the scheduler's CPU, not the worker's: every thread of the driver and of
    # the browser it started.
    pids = subprocess.run(["pgrep", "-f", "chromium|chromedriver"], capture_output=True, text=True).stdout.split()
    for pid in pids:
        subprocess.run(["taskset", "-a", "-p", "-c", "1", pid], capture_output=True)
    return driver


class PageLikeWatcher:
    """What the job page asks of the scheduler while a job renders: its event stream, read as it
    comes, and its live image every 300 ms (the page's throttle), on a thread of its own."""

    def __init__(self, url, job_id):
        self.url, self.job_id, self.stop, self.images, self.events = url, job_id, threading.Event(), 0, 0
        self.threads = [threading.Thread(target=self._events), threading.Thread(target=self._images)]
        for t in self.threads:
            t.start()

    def _events(self):
        with urllib.request.urlopen(f"{self.url}/api/v1/events?job={self.job_id}", timeout=120) as stream:
            for line in stream:
                if line.startswith(b"event: job"):
                    self.events += 1
                if self.stop.is_set():
                    return

    def _images(self):
        while not self.stop.is_set():
            try:
                with urllib.request.urlopen(f"{self.url}/api/v1/jobs/{self.job_id}/live?frame=0", timeout=30) as r:
                    r.read()
                    self.images += 1
            except urllib.error.HTTPError:
                pass  # nothing rendered yet
            time.sleep(0.3)

    def close(self):
        self.stop.set()
        for t in self.threads:
            t.join()


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--farm", required=True)
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--jobs", type=int, default=1000)
    parser.add_argument("--paints", type=int, default=10)
    parser.add_argument("--spp", default="64")
    args = parser.parse_args()
    farm = os.path.abspath(args.farm)
    cornell = os.path.join(JOBS, "cornell.json")
    result = {}
    with tempfile.TemporaryDirectory() as tmp:
        scheduler, seen = start([farm, "scheduler", "--listen", "127.0.0.1:0", "--data-dir", tmp + "/data",
                                 "--http", "127.0.0.1:0", "--batch-ms", "0", "--log-level", "warn"],
                                r"dashboard on (http://\S+)/", cpu=1)
        address = re.search(r"scheduler listening on (\S+)", seen).group(1)
        url = re.search(r"dashboard on (http://\S+)/", seen).group(1)
        # The measuring process itself shares the scheduler's CPU.
        os.sched_setaffinity(0, {1})
        worker, _ = start([farm, "worker", "--listen", "127.0.0.1:0", "--threads", "1", "--scheduler", address,
                           "--cache-dir", tmp + "/w1", "--log-level", "warn"], r"registered", cpu=0)
        driver = browser()
        try:
            # 1. The job's time, unwatched and watched, alternately.
            plain, page_like, browsed = [], [], []
            job = ["--engine", "path", "--width", "256", "--height", "256", "--spp", args.spp, "--tile-size", "16"]
            submit_one = lambda: submit(farm, address, cornell, *job)
            wait_done(farm, address, submit_one())  # warm: the worker has the scene from now on
            requests = []
            for _ in range(args.rounds):
                driver.get("about:blank")
                plain.append(wait_done(farm, address, submit_one())["render_seconds"])
                job_id = submit_one()
                watcher = PageLikeWatcher(url, job_id)
                page_like.append(wait_done(farm, address, job_id)["render_seconds"])
                watcher.close()
                requests.append({"events": watcher.events, "live_images": watcher.images})
                job_id = submit_one()
                driver.get(f"{url}/job.html?id={job_id}")
                browsed.append(wait_done(farm, address, job_id)["render_seconds"])
            result["job_seconds_unwatched"] = plain
            result["job_seconds_watched_by_page_like_client"] = page_like
            result["job_seconds_watched_by_chromium"] = browsed
            result["page_like_client_requests"] = requests
            result["page_like_over_unwatched"] = statistics.median(page_like) / statistics.median(plain)
            result["chromium_over_unwatched"] = statistics.median(browsed) / statistics.median(plain)

            # 2. The job page's first paint with many jobs in the store.
            if args.jobs > 0:
                tiny = ["--engine", "raster", "--width", "16", "--height", "16", "--spp", "1"]
                started = time.monotonic()
                ids = []
                for _ in range(args.jobs):
                    ids.append(submit(farm, address, cornell, *tiny))
                result["jobs_submitted"] = len(ids) + 2 * args.rounds + 1
                result["submit_seconds"] = time.monotonic() - started
                wait_done(farm, address, ids[-1])
                result.update(dashboard_check.job_page_paints(driver, url, ids[len(ids) // 2], args.paints))
                driver.get(url + "/")
                time.sleep(1)
                result["jobs_page_rows"] = driver.execute_script("return document.querySelectorAll('#jobs tbody tr').length")
        finally:
            driver.quit()
            worker.terminate()
            scheduler.terminate()
            worker.wait()
            scheduler.wait()
    print(json.dumps(result, indent=2))
    return 0


if __name__ == "__main__":
    sys.exit(main())
