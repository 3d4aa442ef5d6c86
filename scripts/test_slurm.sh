#!/usr/bin/env bash
# deploy/slurm/visage.sbatch on a real scheduler: a single-node Slurm cluster (slurmctld,
# slurmd and munged on localhost, started here and stopped on exit, state in a temporary
# folder) runs the array job as written over 12 short clips in 4 tasks; one task is cancelled
# while a clip is half written, `visage batch status` then reports missing clips, the job is
# submitted again and finishes every clip exactly once.
#
#   scripts/test_slurm.sh [VISAGE_BINARY]   (default target/debug/visage)
#
# Needs Debian's slurmctld, slurmd, slurm-client and munge (scripts/setup.sh --ci installs
# them as root), FFmpeg, ../shared and the model files. Where Slurm cannot start (packages
# absent, not root) it says why and skips; with CI=true a missing package is a failure.
set -euo pipefail
cd "$(dirname "$0")/.."
repo=$(pwd)
visage=$(realpath "${1:-target/debug/visage}")
models=$(realpath "${VISAGE_MODELS:-models}")
video=../shared/data/video/lp_d18.mp4

skip() {
  echo "test_slurm: SKIPPED: $*"
  exit 0
}
for tool in slurmctld slurmd sbatch squeue scancel scontrol munged; do
  if ! command -v "$tool" >/dev/null 2>&1 && [ ! -x "/usr/sbin/$tool" ]; then
    [ "${CI:-}" = true ] && { echo "test_slurm: FAILED: $tool is not installed (scripts/setup.sh --ci installs Slurm)"; exit 1; }
    skip "$tool is not installed (Debian: slurmctld slurmd slurm-client munge)"
  fi
done
[ "$(id -u)" = 0 ] || skip "the daemons run as root here and this is user $(id -un)"
[ -f "$video" ] || skip "no $video (../shared is absent)"
[ -x "$visage" ] || { echo "test_slurm: FAILED: no visage binary at $visage"; exit 1; }
PATH=/usr/sbin:$PATH

tmp=$(mktemp -d /tmp/visage-slurm.XXXXXX)
pids=()
cleanup() {
  for p in "${pids[@]}"; do kill "$p" 2>/dev/null || true; done
  for p in "${pids[@]}"; do wait "$p" 2>/dev/null || true; done
  [ "${KEEP:-}" = 1 ] || rm -rf "$tmp"
}
trap cleanup EXIT
fail() {
  echo "test_slurm: FAILED: $*"
  for log in "$tmp"/*.log "$tmp"/work/*.out; do
    [ -f "$log" ] && { echo "--- $log"; tail -n 20 "$log"; }
  done
  exit 1
}

# munge: a key of our own, its socket in the temporary folder.
mkdir -p "$tmp/munge" "$tmp/munge-run" "$tmp/state" "$tmp/spool" "$tmp/work"
chmod 700 "$tmp/munge"
chmod 755 "$tmp" "$tmp/munge-run"
mungekey --create --keyfile="$tmp/munge/munge.key" 2>/dev/null ||
  dd if=/dev/urandom of="$tmp/munge/munge.key" bs=1024 count=1 status=none
chmod 600 "$tmp/munge/munge.key"
munged --foreground --force --key-file="$tmp/munge/munge.key" \
  --socket="$tmp/munge-run/munge.socket" --pid-file="$tmp/munge-run/munged.pid" \
  --seed-file="$tmp/munge/seed" --log-file="$tmp/munged.log" >"$tmp/munged.stdout.log" 2>&1 &
pids+=($!)

host=$(hostname -s)
cpus=$(nproc)
mem=$(($(awk '/MemTotal/ {print $2}' /proc/meminfo) / 1024 * 9 / 10))
# Ports away from the defaults, so that a Slurm already on the machine is not disturbed.
port=$((17000 + RANDOM % 2000))
cat > "$tmp/slurm.conf" <<EOF
ClusterName=visage-test
SlurmctldHost=$host
SlurmctldPort=$port
SlurmdPort=$((port + 1))
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
AuthInfo=socket=$tmp/munge-run/munge.socket
CredType=cred/munge
StateSaveLocation=$tmp/state
SlurmdSpoolDir=$tmp/spool/%n
SlurmctldPidFile=$tmp/slurmctld.pid
SlurmdPidFile=$tmp/slurmd.pid
SlurmctldLogFile=$tmp/slurmctld.log
SlurmdLogFile=$tmp/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
MpiDefault=none
ReturnToService=2
SchedulerType=sched/backfill
MinJobAge=600
NodeName=$host CPUs=$cpus RealMemory=$mem State=UNKNOWN
PartitionName=test Nodes=$host Default=YES MaxTime=INFINITE State=UP
EOF
export SLURM_CONF=$tmp/slurm.conf
sleep 1
slurmctld -D -i >"$tmp/slurmctld.stdout.log" 2>&1 &
pids+=($!)
slurmd -D -N "$host" >"$tmp/slurmd.stdout.log" 2>&1 &
pids+=($!)
for _ in $(seq 100); do
  sinfo -h -o %T 2>/dev/null | grep -qE '^(idle|mixed|allocated)' && break
  sleep 0.2
done
sinfo -h -o %T 2>/dev/null | grep -qE '^(idle|mixed|allocated)' ||
  skip "Slurm did not start here: $(tail -n 3 "$tmp/slurmctld.log" "$tmp/slurmd.log" 2>/dev/null | tr '\n' ' ')"
echo "test_slurm: single-node cluster up ($host, $cpus CPUs, port $port)"

# 12 clips of 16 frames, cut from the sample video.
clips=$tmp/work/clips
mkdir -p "$clips"
: > "$tmp/work/manifest.txt"
for i in $(seq 0 11); do
  ffmpeg -v error -y -ss "$(awk "BEGIN { print 0.25 * $i }")" -i "$video" -frames:v 16 -vf scale=240:240 \
    -c:v libx264 -preset ultrafast -pix_fmt yuv420p "$clips/clip$i.mp4"
  echo "clips/clip$i.mp4" >> "$tmp/work/manifest.txt"
done

out=$tmp/work/out
submit() {
  (cd "$tmp/work" && VISAGE="$visage" sbatch --parsable --array=0-3 "$@" \
    "$repo/deploy/slurm/visage.sbatch" manifest.txt out -- --models "$models")
}
job=$(submit)
echo "test_slurm: submitted array job $job (4 tasks)"
# Cancel the task that is running once a clip of it is half written (a point cache with
# frames in it, still under its temporary name, in out/.partial/).
victim=
for _ in $(seq 3000); do
  if compgen -G "$out/.partial/*/sequence.pc2.tmp" >/dev/null; then
    for f in "$out"/.partial/*/sequence.pc2.tmp; do
      if [ -s "$f" ]; then
        victim=$(squeue -h -j "$job" -t R -o %K | head -n 1)
        break
      fi
    done
  fi
  [ -n "$victim" ] && break
  sleep 0.05
done
[ -n "$victim" ] || fail "no task wrote a point cache"
scancel "${job}_${victim}"
echo "test_slurm: cancelled task $victim part-way through a clip"
for _ in $(seq 1200); do
  [ -z "$(squeue -h -j "$job" 2>/dev/null)" ] && break
  sleep 0.1
done
[ -z "$(squeue -h -j "$job" 2>/dev/null)" ] || fail "job $job did not finish"
scontrol show job "${job}_${victim}" | grep -q "JobState=CANCELLED" ||
  fail "task $victim is not cancelled: $(scontrol show job "${job}_${victim}" | grep JobState)"
set +e
"$visage" batch status "$out" > "$tmp/status1.txt" 2>&1
code=$?
set -e
[ "$code" = 4 ] || fail "batch status after the cancel exited $code, not 4 (missing): $(cat "$tmp/status1.txt")"
grep -q "missing (shard $victim)" "$tmp/status1.txt" || fail "status names no missing clip of shard $victim"

job2=$(submit --wait) || fail "the resubmitted job $job2 failed"
echo "test_slurm: resubmitted as $job2; it finished"
"$visage" batch status "$out" > "$tmp/status2.txt" || fail "batch status after the resubmission: $(cat "$tmp/status2.txt")"
done_count=$(find "$out" -name done.json | wc -l)
[ "$done_count" = 12 ] || fail "$done_count clips have done.json, not 12"
[ ! -e "$out/.partial" ] || fail "out/.partial is left: $(ls "$out/.partial")"
# The cancelled task stopped after a frame (SIGTERM) and placed nothing half done; its
# resubmission did the clip again.
grep -q "interrupted; not placed" "$tmp"/work/visage-"${job}"_"${victim}".out ||
  fail "the cancelled task $victim did not stop as interrupted"
grep -q ": done, " "$tmp"/work/visage-"${job2}"_"${victim}".out ||
  fail "the resubmitted task $victim did no clip"
skipped=$(cat "$tmp"/work/visage-"${job2}"_*.out | grep -c "done before; skipped" || true)
redone=$(cat "$tmp"/work/visage-"${job2}"_*.out | grep -c ": done, " || true)
[ "$((skipped + redone))" = 12 ] || fail "the resubmission skipped $skipped and did $redone clips, not 12 in all"
[ "$redone" -ge 1 ] || fail "the resubmission redid no clip"
echo "test_slurm: ok — 12 clips done exactly once ($redone redone after the cancel, $skipped skipped)"
