#!/usr/bin/env bash
# The batch deploy files as written: the Kubernetes Indexed Job validated against the
# Kubernetes schemas (PyPI kubernetes-validate, strict: unknown fields are errors) and checked
# against what `visage batch` reads (completions = $VISAGE_SHARD_COUNT, the batch command, the
# data volume mounted); the Slurm script parsed by bash (scripts/test_slurm.sh runs it on a
# real scheduler); the container build using the project's set-up script.
# The validator comes from the pinned environment scripts/setup.sh --ci makes under target/;
# without it this says so and skips (with CI=true it fails).
set -euo pipefail
cd "$(dirname "$0")/.."
venv="${CARGO_TARGET_DIR:-target}/deploy-venv"
if [ ! -x "$venv/bin/kubernetes-validate" ]; then
  [ "${CI:-}" = true ] && { echo "test_deploy: FAILED: no $venv (scripts/setup.sh --ci makes it)"; exit 1; }
  echo "test_deploy: SKIPPED: no $venv with kubernetes-validate (scripts/setup.sh --ci makes it)"
  exit 0
fi
job=deploy/kubernetes/indexed-job.yaml
# 1.33: the first release with backoffLimitPerIndex and the FailIndex action generally available.
"$venv/bin/kubernetes-validate" --strict --quiet -k 1.33.0 "$job"
"$venv/bin/python" - "$job" <<'PY'
import sys, yaml
job = yaml.safe_load(open(sys.argv[1]))
spec = job["spec"]
assert spec["completionMode"] == "Indexed", "completionMode must be Indexed"
pod = spec["template"]["spec"]
(c,) = [c for c in pod["containers"] if c["name"] == "visage"]
env = {e["name"]: e.get("value") for e in c.get("env", [])}
assert env.get("VISAGE_SHARD_COUNT") == str(spec["completions"]), \
    f"VISAGE_SHARD_COUNT {env.get('VISAGE_SHARD_COUNT')} != completions {spec['completions']}"
assert c["args"][0] == "batch" and "--out" in c["args"], c["args"]
mounts = {m["name"]: m["mountPath"] for m in c["volumeMounts"]}
volumes = {v["name"] for v in pod["volumes"]}
assert set(mounts) <= volumes, f"mounts {mounts} without volumes {volumes}"
data = mounts["data"]
assert c["args"][1].startswith(data) and c["args"][c["args"].index("--out") + 1].startswith(data), \
    "the manifest and the outputs must be on the data volume"
codes = [r["onExitCodes"]["values"] for r in spec["podFailurePolicy"]["rules"]]
assert [3] in codes or any(3 in v for v in codes), "exit code 3 (failed clips) must not be retried"
print(f"test_deploy: {sys.argv[1]}: valid, {spec['completions']} shards, data on {data}")
PY
bash -n deploy/slurm/visage.sbatch
grep -q '^#SBATCH --array=' deploy/slurm/visage.sbatch
grep -q 'scripts/setup.sh' deploy/container/Containerfile
echo "test_deploy: ok"
