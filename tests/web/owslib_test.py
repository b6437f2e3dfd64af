#!/usr/bin/python3
"""satmesh-server as an OGC API - Processes client sees it: OWSLib (Debian's
python3-owslib) reads the landing page, the OpenAPI document, the conformance classes, the
process list and the process description; then the execute request is built from what the
description declares ({"inputs": {"job": JOB}}, Prefer: respond-async) and posted to the
process's execute link, the job is followed through its statusInfo to its results link,
found in the job list, and a second job is dismissed. Links are followed, not built.
Exit 77 (skip) only where OWSLib is absent.

  owslib_test.py SATMESH SATMESH_SERVER
"""
import json
import subprocess
import sys
import tempfile
import time
import urllib.error
import urllib.request

try:
    from owslib.ogcapi.processes import Processes
except ImportError:
    print("SKIP: OWSLib (Debian package python3-owslib) is not installed")
    sys.exit(77)

OGC_REL = "http://www.opengis.net/def/rel/ogc/1.0/"
CONF = "http://www.opengis.net/spec/ogcapi-processes-1/1.0/conf/"


def link(doc, rel):
    hrefs = [l["href"] for l in doc.get("links", []) if l.get("rel") == rel]
    assert hrefs, f"no link rel={rel} in {json.dumps(doc)[:300]}"
    return hrefs[0]


def request(url, method="GET", body=None, headers=None):
    data = json.dumps(body).encode() if body is not None else None
    req = urllib.request.Request(url, data=data, method=method, headers=headers or {})
    if data is not None:
        req.add_header("Content-Type", "application/json")
    try:
        with urllib.request.urlopen(req, timeout=30) as r:
            return r.status, dict(r.headers), json.loads(r.read() or b"null")
    except urllib.error.HTTPError as e:
        return e.code, dict(e.headers), json.loads(e.read() or b"null")


def main():
    satmesh, server_bin = sys.argv[1], sys.argv[2]
    with tempfile.TemporaryDirectory() as work:
        subprocess.run([satmesh, "synth", "--preset", "small", "--out", f"{work}/scene"], check=True,
                       stdout=subprocess.DEVNULL)
        log = open(f"{work}/server.log", "w+")
        server = subprocess.Popen([server_bin, "--port", "0", "--data-dir", f"{work}/data", "--data-root",
                                   f"{work}/scene", "--workers", "2"], stdout=log, stderr=subprocess.STDOUT)
        try:
            port = None
            for _ in range(100):
                with open(f"{work}/server.log") as f:
                    ports = [l.split()[-1] for l in f if l.startswith("listening on port ")]
                if ports:
                    port = int(ports[0])
                    break
                time.sleep(0.1)
            assert port, "the server did not start: " + open(f"{work}/server.log").read()
            run(f"http://127.0.0.1:{port}", f"{work}/scene/job.json")
        finally:
            server.terminate()
            server.wait(timeout=30)


def run(base, job_file):
    # OWSLib: landing page, OpenAPI, conformance, processes, description.
    api = Processes(base)
    assert any(l["rel"] == OGC_REL + "processes" for l in api.links), api.links
    openapi = api.api()
    assert openapi["openapi"].startswith("3.0"), openapi.get("openapi")
    conforms = api.conformance()["conformsTo"]
    for c in ("core", "json", "job-list", "dismiss"):
        assert CONF + c in conforms, f"conformance: no {c}"
    processes = api.processes()["processes"]
    assert [p["id"] for p in processes] == ["refine-mesh"], processes
    description = api.process("refine-mesh")
    assert list(description["inputs"]) == ["job"], description["inputs"]
    assert "async-execute" in description["jobControlOptions"]
    schema = description["inputs"]["job"]["schema"]
    print(f"OWSLib: landing {len(api.links)} links, OpenAPI {openapi['openapi']}, {len(conforms)} conformance "
          f"classes, process refine-mesh with input 'job' ({len(schema['properties'])} schema properties)")

    # Execute exactly as described: the declared input, async, at the execute link.
    with open(job_file) as f:
        job = json.load(f)  # hrefs relative to the server's data root (the scene folder)
    job.setdefault("options", {})["iterations_per_level"] = 3
    assert set(job) <= set(schema["properties"]), f"job fields {set(job)} not in the schema"
    execute = link(description, OGC_REL + "execute")
    status, headers, info = request(execute, "POST", {"inputs": {"job": job}}, {"Prefer": "respond-async"})
    assert status == 201, (status, info)
    assert headers.get("Preference-Applied") == "respond-async", headers
    assert info["type"] == "process" and info["status"] in ("accepted", "running", "successful"), info
    job_id = info["jobID"]
    monitor = base + headers["Location"] if headers["Location"].startswith("/") else headers["Location"]
    t0 = time.time()
    while info["status"] in ("accepted", "running") and time.time() - t0 < 300:
        time.sleep(0.5)
        _, _, info = request(monitor)
    assert info["status"] == "successful", info
    print(f"job {job_id}: {info['status']} in {time.time() - t0:.1f} s, progress {info['progress']}")

    # Results through the statusInfo's link; the tileset through the results' links.
    status, _, results = request(link(info, OGC_REL + "results"))
    assert status == 200, results
    status, _, tileset = request(link(results, "tileset"))
    assert status == 200 and tileset["asset"]["version"] == "1.1", tileset
    assert results["metrics"]["value"]["gsd_m"] > 0.2, results["metrics"]["value"]["gsd_m"]
    # The job list (landing page's job-list link) has it.
    _, _, jobs = request(link({"links": api.links}, OGC_REL + "job-list"))
    assert job_id in [j["jobID"] for j in jobs["jobs"]], jobs

    # Dismiss: a second job, deleted through its statusInfo's self link.
    job["options"]["iterations_per_level"] = 20
    status, headers, second = request(execute, "POST", {"inputs": {"job": job}}, {"Prefer": "respond-async"})
    assert status == 201, second
    status, _, dismissed = request(link(second, "self"), "DELETE")
    assert status == 200 and dismissed["status"] == "dismissed", (status, dismissed)
    print(f"results: tileset with {len(tileset['root']['children'])} tile(s), gsd "
          f"{results['metrics']['value']['gsd_m']:.3f} m; job list has the job; second job dismissed")


if __name__ == "__main__":
    main()
