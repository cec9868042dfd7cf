#!/usr/bin/env python3
"""deploy/k8s: schema check of the manifests, and their enavi command lines run for real.

No cluster exists here, and kubectl (Debian's kubernetes-client too) cannot validate without
one: `kubectl apply --dry-run=client --validate=true` downloads the OpenAPI schema from the API
server. So this checks the manifests against a JSON schema of the subset of the Kubernetes API
(v1, apps/v1, batch/v1; field names and types as in the API reference) that the manifests use:
kinds and apiVersions, required fields, types, and no unknown field on the objects covered (a
typo such as `volumeMount` or `replica` fails). It does not check what only a server knows
(admission, defaulting, quota). Then it cross-checks the references (Secret, ConfigMap, Service
selectors, named ports, volumes), that worker CPU requests equal --slots, and runs the server's
and the worker's exact argument lists with the real enavi binary on loopback (paths and the
server's pod name mapped to this machine): the worker must join the server.

    k8s_manifests_test.py BUILD_DIR SOURCE_DIR
"""
import csv
import json
import os
import pathlib
import re
import shutil
import signal
import subprocess
import sys
import tempfile
import time
import urllib.request

import jsonschema
import yaml


def obj(props, required=(), extra=False):
    """An object schema; unknown properties fail unless `extra`."""
    s = {"type": "object", "properties": props, "required": list(required)}
    if not extra:
        s["additionalProperties"] = False
    return s


STR = {"type": "string"}
INT = {"type": "integer"}
BOOL = {"type": "boolean"}
STRMAP = {"type": "object", "additionalProperties": STR}
QUANTITY = {"type": "string", "pattern": r"^[0-9]+(\.[0-9]+)?(m|Ki|Mi|Gi|Ti|k|M|G|T)?$"}
NAME = {"type": "string", "pattern": r"^[a-z0-9]([-a-z0-9]*[a-z0-9])?$", "maxLength": 63}
def arr(items): return {"type": "array", "items": items}

METADATA = obj({"name": NAME, "labels": STRMAP, "annotations": STRMAP, "namespace": NAME}, ["name"])
RESOURCES = obj({"requests": obj({"cpu": QUANTITY, "memory": QUANTITY}),
                 "limits": obj({"cpu": QUANTITY, "memory": QUANTITY})})
PORT_REF = {"anyOf": [INT, STR]}
KEY_REF = obj({"name": NAME, "key": STR, "optional": BOOL}, ["name", "key"])
ENV = obj({"name": STR, "value": STR,
           "valueFrom": obj({"secretKeyRef": KEY_REF, "configMapKeyRef": KEY_REF})}, ["name"])
PROBE = obj({"tcpSocket": obj({"port": PORT_REF}, ["port"]),
             "httpGet": obj({"path": STR, "port": PORT_REF}, ["port"]),
             "periodSeconds": INT, "initialDelaySeconds": INT, "failureThreshold": INT})
CONTAINER = obj({
    "name": NAME, "image": STR, "command": arr(STR), "args": arr(STR), "env": arr(ENV),
    "ports": arr(obj({"name": STR, "containerPort": INT,
                      "protocol": {"enum": ["TCP", "UDP", "SCTP"]}}, ["containerPort"])),
    "readinessProbe": PROBE, "livenessProbe": PROBE, "resources": RESOURCES,
    "volumeMounts": arr(obj({"name": NAME, "mountPath": STR, "readOnly": BOOL},
                            ["name", "mountPath"])),
}, ["name", "image"])
VOLUME = obj({"name": NAME, "emptyDir": obj({"medium": STR, "sizeLimit": QUANTITY}),
              "configMap": obj({"name": NAME}, ["name"]),
              "secret": obj({"secretName": NAME}, ["secretName"]),
              "persistentVolumeClaim": obj({"claimName": NAME}, ["claimName"])}, ["name"])
POD_SPEC = obj({"containers": {**arr(CONTAINER), "minItems": 1}, "volumes": arr(VOLUME),
                "restartPolicy": {"enum": ["Always", "OnFailure", "Never"]},
                "terminationGracePeriodSeconds": INT}, ["containers"])
TEMPLATE = obj({"metadata": obj({"labels": STRMAP}), "spec": POD_SPEC}, ["spec"])
SELECTOR = obj({"matchLabels": STRMAP}, ["matchLabels"])
PVC_SPEC = obj({"accessModes": arr({"enum": ["ReadWriteOnce", "ReadOnlyMany", "ReadWriteMany",
                                             "ReadWriteOncePod"]}),
                "storageClassName": STR,
                "resources": obj({"requests": obj({"storage": QUANTITY}, ["storage"])})},
               ["accessModes", "resources"])


def kind(api_version, name, spec=None, **top):
    props = {"apiVersion": {"const": api_version}, "kind": {"const": name}, "metadata": METADATA}
    required = ["apiVersion", "kind", "metadata"]
    if spec is not None:
        props["spec"] = spec
        required.append("spec")
    props.update(top)
    return obj(props, required)


SCHEMAS = {
    "ConfigMap": kind("v1", "ConfigMap", data=STRMAP),
    "Secret": kind("v1", "Secret", type=STR, stringData=STRMAP, data=STRMAP),
    "Service": kind("v1", "Service", obj({
        "selector": STRMAP, "clusterIP": STR, "publishNotReadyAddresses": BOOL,
        "type": {"enum": ["ClusterIP", "NodePort", "LoadBalancer"]},
        "ports": {**arr(obj({"name": STR, "port": INT, "targetPort": PORT_REF,
                             "protocol": {"enum": ["TCP", "UDP", "SCTP"]}}, ["port"])),
                  "minItems": 1}}, ["ports"])),
    "StatefulSet": kind("apps/v1", "StatefulSet", obj({
        "serviceName": STR, "replicas": INT, "selector": SELECTOR, "template": TEMPLATE,
        "volumeClaimTemplates": arr(obj({"metadata": obj({"name": NAME}, ["name"]),
                                         "spec": PVC_SPEC}, ["metadata", "spec"]))},
        ["selector", "template", "serviceName"])),
    "Deployment": kind("apps/v1", "Deployment", obj({
        "replicas": INT, "selector": SELECTOR, "template": TEMPLATE}, ["selector", "template"])),
    "Job": kind("batch/v1", "Job", obj({
        "parallelism": INT, "completions": INT, "backoffLimit": INT,
        "activeDeadlineSeconds": INT, "template": TEMPLATE}, ["template"])),
}

failures = []


def check(condition, message):
    if not condition:
        failures.append(message)


def load(k8s_dir):
    docs = []
    for path in sorted(k8s_dir.glob("*.yaml")):
        for doc in yaml.safe_load_all(path.read_text()):
            if doc is None:
                continue
            where = f"{path.name}: {doc.get('kind')}/{doc.get('metadata', {}).get('name')}"
            schema = SCHEMAS.get(doc.get("kind"))
            if schema is None:
                failures.append(f"{where}: kind not covered by the schema check")
                continue
            for error in jsonschema.Draft7Validator(schema).iter_errors(doc):
                field = ".".join(str(p) for p in error.absolute_path) or "(top)"
                failures.append(f"{where}: {field}: {error.message}")
            docs.append((where, doc))
    return docs


def pod_specs(docs):
    for where, doc in docs:
        if doc["kind"] in ("StatefulSet", "Deployment", "Job"):
            yield where, doc, doc["spec"]["template"]


def cpu_cores(q):
    return float(q[:-1]) / 1000 if q.endswith("m") else float(q)


def check_references(docs):
    """Names the manifests use exist, selectors select, CPU requests match --slots."""
    names = {(doc["kind"], doc["metadata"]["name"]) for _, doc in docs}
    services = {doc["metadata"]["name"]: doc for _, doc in docs if doc["kind"] == "Service"}
    for where, doc, template in pod_specs(docs):
        labels = template.get("metadata", {}).get("labels", {})
        selector = doc["spec"].get("selector", {}).get("matchLabels", {})
        check(all(labels.get(k) == v for k, v in selector.items()),
              f"{where}: spec.selector does not match the pod template's labels")
        volumes = {v["name"]: v for v in template["spec"].get("volumes", [])}
        claims = {c["metadata"]["name"] for c in doc["spec"].get("volumeClaimTemplates", [])}
        for v in volumes.values():
            if "configMap" in v:
                check(("ConfigMap", v["configMap"]["name"]) in names,
                      f"{where}: volume {v['name']}: no ConfigMap {v['configMap']['name']}")
        if doc["kind"] == "StatefulSet":
            check(doc["spec"]["serviceName"] in services and
                  services[doc["spec"]["serviceName"]]["spec"].get("clusterIP") == "None",
                  f"{where}: serviceName must be a headless Service of these manifests")
        for c in template["spec"]["containers"]:
            for m in c.get("volumeMounts", []):
                check(m["name"] in volumes or m["name"] in claims,
                      f"{where}: container {c['name']}: volumeMount {m['name']} has no volume")
            for e in c.get("env", []):
                ref = e.get("valueFrom", {}).get("secretKeyRef")
                if ref:
                    check(("Secret", ref["name"]) in names, f"{where}: no Secret {ref['name']}")
            args = c.get("args", [])
            if c.get("command") == ["enavi", "worker"]:
                slots = int(args[args.index("--slots") + 1]) if "--slots" in args else 1
                cpu = c.get("resources", {}).get("requests", {}).get("cpu")
                check(cpu is not None and cpu_cores(cpu) == slots,
                      f"{where}: worker requests cpu {cpu}, want {slots} (--slots {slots})")
    for name, svc in services.items():
        selector = svc["spec"].get("selector", {})
        matched = [t for _, _, t in pod_specs(docs)
                   if all(t.get("metadata", {}).get("labels", {}).get(k) == v
                          for k, v in selector.items())]
        check(len(matched) >= 1, f"Service {name}: selector matches no pod template")
        for p in svc["spec"]["ports"]:
            target = p.get("targetPort")
            if isinstance(target, str):
                check(any(target == cp.get("name") for t in matched
                          for c in t["spec"]["containers"] for cp in c.get("ports", [])),
                      f"Service {name}: targetPort {target} is no container port of its pods")


def container(docs, command):
    for where, _, template in pod_specs(docs):
        for c in template["spec"]["containers"]:
            if c.get("command", [])[:len(command)] == command:
                yield where, c


def run_commands(docs, enavi, fake_episode, workdir):
    """The server's and worker's argument lists, for real: paths under `workdir`, the server pod's
    name and eth0 mapped to loopback, port 0 for HTTP, a private domain and partition."""
    cyclone = next(doc for _, doc in docs if doc["kind"] == "ConfigMap"
                   and doc["metadata"]["name"] == "enavi-cyclonedds")["data"]["cyclonedds.xml"]
    check('<Peer address="enavi-server-0.enavi-dds"/>' in cyclone,
          "cyclonedds.xml: the workers' peer must be the server pod enavi-server-0.enavi-dds")
    (workdir / "etc").mkdir()
    (workdir / "etc/cyclonedds.xml").write_text(
        cyclone.replace("enavi-server-0.enavi-dds", "127.0.0.1").replace('name="eth0"', 'name="lo"'))
    domain, partition = str(100 + os.getpid() % 100), f"k8s-test-{os.getpid()}"

    def localise(args):
        out = []
        for a in args:
            a = a.replace("/etc/enavi/", f"{workdir}/etc/").replace("/data/", f"{workdir}/data/")
            a = a.replace("/var/lib/enavi/", f"{workdir}/state/")
            out.append(a)
        for flag, value in (("--domain", domain), ("--partition", partition)):
            check(flag in out, f"{flag} missing: server and workers must agree on it")
            if flag in out:
                out[out.index(flag) + 1] = value
        return out

    (workdir / "data").mkdir()
    procs = []
    try:
        where, server = next(container(docs, ["enavi", "serve"]))
        args = localise(server["args"])
        check("--http" in args and args[args.index("--http") + 1] == "0.0.0.0:8717",
              f"{where}: the server must listen on 0.0.0.0:8717 (the Services' target)")
        args[args.index("--http") + 1] = "127.0.0.1:0"
        ready = workdir / "ready"
        env = dict(os.environ, ENAVI_TOKEN="k8s-test-token")
        log = open(workdir / "serve.log", "w")
        procs.append(subprocess.Popen([enavi, "serve", *args, "--ready-file", str(ready)],
                                      env=env, stdout=log, stderr=log))
        for _ in range(300):
            if ready.exists() or procs[0].poll() is not None:
                break
            time.sleep(0.1)
        check(ready.exists(), f"{where}: enavi serve {' '.join(args)} did not start: "
                              f"{(workdir / 'serve.log').read_text()[-2000:]}")
        if not ready.exists():
            return
        url = ready.read_text().strip()
        for where, worker in container(docs, ["enavi", "worker"]):
            args = localise(worker["args"]) + ["--episode-cmd", fake_episode]
            log = open(workdir / "worker.log", "w")
            procs.append(subprocess.Popen([enavi, "worker", *args], stdout=log, stderr=log))
            joined = False
            for _ in range(300):
                with urllib.request.urlopen(f"{url}/api/workers", timeout=5) as r:
                    if json.load(r):
                        joined = True
                        break
                if procs[-1].poll() is not None:
                    break
                time.sleep(0.1)
            check(joined, f"{where}: enavi worker {' '.join(args)} did not join: "
                          f"{(workdir / 'worker.log').read_text()[-2000:]}")
        # The batch Job's shell command, as written, with this enavi on PATH and the spec at its
        # mount point mapped: it must submit, wait and print one CSV row per episode.
        spec_doc = next(doc for _, doc in docs if doc["kind"] == "ConfigMap"
                        and doc["metadata"]["name"] == "enavi-batch-spec")
        (workdir / "batch").mkdir()
        (workdir / "batch/job.yaml").write_text(spec_doc["data"]["job.yaml"])
        for where, job in container(docs, ["sh", "-c"]):
            script = job["command"][2].replace("/etc/enavi-batch/", f"{workdir}/batch/")
            env = dict(os.environ, PATH=f"{pathlib.Path(enavi).parent}:{os.environ['PATH']}",
                       ENAVI_SERVER=url, ENAVI_TOKEN="k8s-test-token")
            batch = subprocess.run(["sh", "-c", script], env=env, capture_output=True, text=True,
                                   timeout=120)
            lines = batch.stdout.strip().splitlines()
            header = next((i for i, line in enumerate(lines)
                           if "episode_id" in line.split(",")), None)
            rows = lines[header + 1:] if header is not None else []
            if rows:
                records = list(csv.DictReader(lines[header:]))
                check(len({r["episode_id"] for r in records}) == len(rows),
                      f"{where}: duplicate episode ids in the batch's results")
            check("failed:" not in batch.stdout, f"{where}: episodes failed: {batch.stdout[-1000:]}")
            episodes = subprocess.run([enavi, "submit", "--dry-run", str(workdir / "batch/job.yaml")],
                                      capture_output=True, text=True)
            want = re.search(r"(\d+) episodes", episodes.stdout + episodes.stderr)
            check(batch.returncode == 0 and want is not None and len(rows) == int(want.group(1)),
                  f"{where}: the batch command gave exit {batch.returncode} and {len(rows)} CSV "
                  f"rows, want {want.group(1) if want else '?'}: {batch.stdout[-1000:]} "
                  f"{batch.stderr[-2000:]}")
    finally:
        for p in procs:
            p.send_signal(signal.SIGTERM)
        for p in procs:
            try:
                p.wait(timeout=30)
            except subprocess.TimeoutExpired:
                p.kill()


def main():
    build, source = pathlib.Path(sys.argv[1]).resolve(), pathlib.Path(sys.argv[2]).resolve()
    docs = load(source / "deploy/k8s")
    check(len(docs) >= 8, f"expected the 8 objects of deploy/k8s, found {len(docs)}")
    check_references(docs)
    workdir = pathlib.Path(tempfile.mkdtemp(prefix="enavi-k8s-"))
    try:
        run_commands(docs, str(build / "bin/enavi"), str(build / "tests/fake_episode"), workdir)
    finally:
        shutil.rmtree(workdir, ignore_errors=True)
    for f in failures:
        print("FAIL:", f)
    if not failures:
        print(f"deploy/k8s: {len(docs)} objects valid; server and worker command lines ran")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
