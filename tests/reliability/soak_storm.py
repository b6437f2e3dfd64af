#!/usr/bin/env python3
"""Soak and storm of a real satmesh-server (RELIABILITY.md).

  soak:  N small real jobs (a synthetic scene, a 12 m AOI, one level, one iteration) one
         after another; the server's RSS (VmRSS) and open file descriptors are sampled
         after every job. Fails when, after the first 10% of the jobs (warm-up: caches,
         thread pools, GDAL's), RSS grows by more than --rss-bound-mb or fds by more than 4.
  storm: S concurrent submissions of that job and C concurrent status requests, all
         released at once; reports p50/p99/max latency per kind, the answers by status,
         and checks that the server still answers /health and that every job finishes.

  python3 tests/reliability/soak_storm.py --build build --jobs 200 --storm-status 500 --storm-submit 50
Prints one JSON document with the figures. Exit 1 when a bound is broken.
"""
import argparse, http.client, json, os, shutil, subprocess, sys, tempfile, threading, time


def request(port, method, path, body=None, timeout=60):
    t0 = time.monotonic()
    conn = http.client.HTTPConnection("127.0.0.1", port, timeout=timeout)
    try:
        headers = {"Content-Type": "application/json"} if body is not None else {}
        conn.request(method, path, body=body, headers=headers)
        r = conn.getresponse()
        data = r.read()
        return r.status, data, time.monotonic() - t0
    except Exception as e:  # a refused or reset connection counts as an answer of 0
        return 0, str(e).encode(), time.monotonic() - t0
    finally:
        conn.close()


def proc_figures(pid):
    rss_kb = 0
    with open(f"/proc/{pid}/status") as f:
        for line in f:
            if line.startswith("VmRSS:"):
                rss_kb = int(line.split()[1])
    return rss_kb / 1024.0, len(os.listdir(f"/proc/{pid}/fd"))


def wait_job(port, job_id, timeout_s=600):
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        status, data, _ = request(port, "GET", f"/jobs/{job_id}")
        if status == 200:
            info = json.loads(data)
            if info["status"] not in ("accepted", "running"):
                return info
        time.sleep(0.05)
    raise RuntimeError(f"job {job_id} did not finish in {timeout_s} s")


def percentile(values, q):
    if not values:
        return None
    v = sorted(values)
    return v[min(len(v) - 1, int(round(q / 100.0 * (len(v) - 1))))]


def small_job(scene):
    with open(os.path.join(scene, "job.json")) as f:
        job = json.load(f)
    for image in job["images"]:
        image["href"] = os.path.join(scene, image["href"])
    job["initial"]["dsm"] = os.path.join(scene, job["initial"]["dsm"])
    job.setdefault("options", {}).update({"levels": 1, "iterations_per_level": 1, "estimate_bias": False})
    # A 12 m square at the DSM's centre.
    info = json.loads(subprocess.check_output(["gdalinfo", "-json", job["initial"]["dsm"]]))
    cx, cy = info["cornerCoordinates"]["center"]
    job["aoi"] = {"bbox": [cx - 6, cy - 6, cx + 6, cy + 6]}
    job.pop("tiling", None)
    return job


def soak(port, pid, job, n, rss_bound_mb):
    body = json.dumps(job)
    samples, t0 = [], time.monotonic()
    for i in range(n):
        status, data, _ = request(port, "POST", "/processes/refine-mesh/execution", body)
        if status != 201:
            raise RuntimeError(f"job {i}: HTTP {status}: {data[:300]}")
        info = wait_job(port, json.loads(data)["jobID"])
        if info["status"] != "successful":
            raise RuntimeError(f"job {i}: {info['status']}: {info.get('message')}")
        rss, fds = proc_figures(pid)
        samples.append({"job": i + 1, "rss_mb": round(rss, 1), "fds": fds})
    warm = samples[max(0, n // 10 - 1)]
    last = samples[-1]
    peak = max(s["rss_mb"] for s in samples[n // 10:])
    out = {"jobs": n, "seconds": round(time.monotonic() - t0, 1),
           "rss_mb_after_warmup": warm["rss_mb"], "rss_mb_last": last["rss_mb"], "rss_mb_peak_after_warmup": peak,
           "fds_after_warmup": warm["fds"], "fds_last": last["fds"],
           "every_10th": samples[9::max(1, n // 10)]}
    out["ok"] = peak - warm["rss_mb"] <= rss_bound_mb and last["fds"] - warm["fds"] <= 4
    return out


def storm(port, job, n_status, n_submit):
    status_path = None
    status, data, _ = request(port, "POST", "/processes/refine-mesh/execution", json.dumps(job))
    status_path = f"/jobs/{json.loads(data)['jobID']}"
    barrier = threading.Barrier(n_status + n_submit)
    results = {"status": [], "submit": []}
    lock = threading.Lock()
    body = json.dumps(job)

    def one(kind):
        barrier.wait()
        if kind == "status":
            r = request(port, "GET", status_path, timeout=120)
        else:
            r = request(port, "POST", "/processes/refine-mesh/execution", body, timeout=120)
        with lock:
            results[kind].append(r)

    threads = [threading.Thread(target=one, args=("status",)) for _ in range(n_status)]
    threads += [threading.Thread(target=one, args=("submit",)) for _ in range(n_submit)]
    t0 = time.monotonic()
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    wall = time.monotonic() - t0
    out = {"concurrent_status": n_status, "concurrent_submit": n_submit, "wall_s": round(wall, 2)}
    for kind, rs in results.items():
        lat = [r[2] * 1000 for r in rs]
        codes = {}
        for r in rs:
            codes[str(r[0])] = codes.get(str(r[0]), 0) + 1
        failures = sorted({r[1].decode(errors="replace")[:120] for r in rs if r[0] == 0})
        out[kind] = {"answers": codes, "no_answer_errors": failures[:3], "p50_ms": round(percentile(lat, 50), 1),
                     "p99_ms": round(percentile(lat, 99), 1), "max_ms": round(max(lat), 1)}
    ids = [json.loads(r[1])["jobID"] for r in results["submit"] if r[0] == 201]
    finished = [wait_job(port, i)["status"] for i in ids]
    out["submitted_jobs_successful"] = sum(1 for s in finished if s == "successful")
    health = request(port, "GET", "/health")
    out["health_after"] = health[0]
    out["ok"] = (health[0] == 200 and out["status"]["answers"].get("200", 0) == n_status
                 and out["submit"]["answers"].get("201", 0) == n_submit
                 and out["submitted_jobs_successful"] == n_submit)
    return out


def main():
    p = argparse.ArgumentParser()
    p.add_argument("--build", default="build")
    p.add_argument("--jobs", type=int, default=200)
    p.add_argument("--rss-bound-mb", type=float, default=50)
    p.add_argument("--storm-status", type=int, default=500)
    p.add_argument("--storm-submit", type=int, default=50)
    p.add_argument("--workers", type=int, default=2)
    p.add_argument("--http-threads", type=int, default=32)
    a = p.parse_args()
    work = tempfile.mkdtemp(prefix="satmesh_soak_")
    server = None
    try:
        scene = os.path.join(work, "scene")
        subprocess.run([os.path.join(a.build, "client/satmesh"), "synth", "--out", scene, "--preset", "small",
                        "--seed", "3", "--no-preview"], check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        job = small_job(scene)
        port = 18000 + os.getpid() % 1000
        log = open(os.path.join(work, "server.log"), "w")
        server = subprocess.Popen([os.path.join(a.build, "server/satmesh-server"), "--port", str(port),
                                   "--data-dir", os.path.join(work, "data"), "--data-root", scene,
                                   "--workers", str(a.workers), "--http-threads", str(a.http_threads)],
                                  stdout=log, stderr=subprocess.STDOUT)
        for _ in range(100):
            if request(port, "GET", "/health", timeout=1)[0] == 200:
                break
            time.sleep(0.1)
        report = {"machine": {"cpus": os.cpu_count(), "uname": " ".join(os.uname())},
                  "server": {"workers": a.workers, "http_threads": a.http_threads}}
        if a.jobs > 0:
            report["soak"] = soak(port, server.pid, job, a.jobs, a.rss_bound_mb)
        if a.storm_status + a.storm_submit > 0:
            report["storm"] = storm(port, job, a.storm_status, a.storm_submit)
        rss, fds = proc_figures(server.pid)
        report["server_end"] = {"rss_mb": round(rss, 1), "fds": fds}
        print(json.dumps(report, indent=1))
        return 0 if all(report[k]["ok"] for k in ("soak", "storm") if k in report) else 1
    finally:
        if server:
            server.terminate()
            server.wait(30)
        shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    sys.exit(main())
