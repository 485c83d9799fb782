#!/usr/bin/env bash
# farm_test.sh SPLATFFD REPO: a short clip of the sphere and of a Gaussian cloud rendered as a Slurm job
# array (tools/farm/slurm_render.sbatch), checked with `splatffd assemble`, and compared byte for byte with
# a single-machine render of the same clip.
# Slurm: a single-node cluster started here (munged, slurmctld, slurmd from Debian's packages, a minimal
# slurm.conf in a temporary folder, no systemd, no cgroups: proctrack/linuxproc, task/none), stopped
# again on any exit. It needs root and the packages; without them the test says so and runs the array's
# tasks as parallel local processes with the same variables (SLURM_ARRAY_TASK_ID ...), so the sharding,
# the template and the check are still covered. SFFD_REQUIRE_SLURM=1 makes that fallback a failure.
set -euo pipefail
splatffd=$(realpath "$1")
repo=$(realpath "$2")
template=$repo/tools/farm/slurm_render.sbatch
shards=4
tmp=$(mktemp -d "${TMPDIR:-/tmp}/sffd_farm.XXXXXX")
daemons=()
# Rendering is headless (EGL), as on a farm node without a display.
unset DISPLAY WAYLAND_DISPLAY

cleanup() {
  local pid
  # Jobs still running (a timed-out wait) go first, while slurmctld can still cancel them.
  if [[ ${mode:-} == slurm ]]; then scancel --full --quiet --jobname=splatffd-render 2>/dev/null || true; fi
  for pid in "${daemons[@]}"; do kill "$pid" 2>/dev/null || true; done
  for pid in "${daemons[@]}"; do
    for _ in $(seq 50); do kill -0 "$pid" 2>/dev/null || break; sleep 0.1; done
    kill -9 "$pid" 2>/dev/null || true
  done
  rm -rf "$tmp"
}
trap cleanup EXIT
fail() { echo "farm_test: FAIL: $*" >&2; exit 1; }

# Starts munged, slurmctld and slurmd for this test only; false (with the reason on stderr) if it cannot.
start_slurm() {
  local c
  if [[ $(id -u) != 0 ]]; then echo "farm_test: not root: cannot start slurmd" >&2; return 1; fi
  for c in munged mungekey slurmctld slurmd sbatch sinfo; do
    command -v "$c" >/dev/null || { echo "farm_test: $c not installed (tools/bootstrap.sh installs Slurm)" >&2; return 1; }
  done
  local s=$tmp/slurm host
  host=$(hostname -s)
  mkdir -p "$s/state" "$s/spool" "$s/munge"
  chmod 700 "$s/munge"
  mungekey -c -k "$s/munge/munge.key" -b 1024 || return 1
  chmod 600 "$s/munge/munge.key"
  # --force: munged refuses a socket folder others cannot enter, and this one is private on purpose.
  munged -f --key-file="$s/munge/munge.key" --socket="$s/munge/socket" --pid-file="$s/munge/munged.pid" \
    --log-file="$s/munge/munged.log" --seed-file="$s/munge/seed" || return 1
  daemons+=("$(cat "$s/munge/munged.pid")")
  # Ports of its own, so a cluster already on this machine (or another run of this test) is not touched.
  local port=$((20000 + RANDOM % 20000))
  cat > "$s/slurm.conf" <<CONF
ClusterName=sffdfarmtest
SlurmctldHost=$host
SlurmUser=root
SlurmdUser=root
SlurmctldPort=$port
SlurmdPort=$((port + 1))
AuthType=auth/munge
AuthInfo=socket=$s/munge/socket
CredType=cred/munge
StateSaveLocation=$s/state
SlurmdSpoolDir=$s/spool
SlurmctldPidFile=$s/slurmctld.pid
SlurmdPidFile=$s/slurmd.pid
SlurmctldLogFile=$s/slurmctld.log
SlurmdLogFile=$s/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
ReturnToService=2
MpiDefault=none
NodeName=$host CPUs=$(nproc) State=UNKNOWN
PartitionName=farmtest Nodes=$host Default=YES MaxTime=INFINITE State=UP
CONF
  export SLURM_CONF=$s/slurm.conf
  slurmctld -i -f "$SLURM_CONF" || return 1
  for _ in $(seq 100); do [[ -s $s/slurmctld.pid ]] && break; sleep 0.1; done
  [[ -s $s/slurmctld.pid ]] && daemons+=("$(cat "$s/slurmctld.pid")")
  slurmd -f "$SLURM_CONF" || return 1
  for _ in $(seq 100); do [[ -s $s/slurmd.pid ]] && break; sleep 0.1; done
  [[ -s $s/slurmd.pid ]] && daemons+=("$(cat "$s/slurmd.pid")")
  for _ in $(seq 300); do
    if sinfo -h -o %t 2>/dev/null | grep -qE '^(idle|mix|alloc)'; then return 0; fi
    sleep 0.1
  done
  echo "farm_test: the node did not come up within 30 s; slurmctld.log and slurmd.log end with:" >&2
  tail -n 5 "$s/slurmctld.log" "$s/slurmd.log" >&2 || true
  return 1
}

# The array for one clip: sbatch --array=0..N-1 --wait (bounded), or the tasks as local processes.
run_array() {  # OUT SCENE OPTIONS...
  local out=$1
  shift
  if [[ $mode == slurm ]]; then
    local job
    job=$(cd "$tmp" && SHARDS=$shards OUT=$out SPLATFFD=$splatffd \
      timeout 300 sbatch --parsable --wait --array=0-$((shards - 1)) --output="$tmp/slurm-%A_%a.out" "$template" "$@") ||
      { cat "$tmp"/slurm-*.out >&2 2>/dev/null || true; fail "sbatch --wait failed or timed out for $out"; }
    echo "farm_test: Slurm job $job finished ($shards tasks)"
  else
    local k pids=()
    for ((k = 0; k < shards; ++k)); do
      SLURM_ARRAY_JOB_ID=local SLURM_ARRAY_TASK_ID=$k SLURM_ARRAY_TASK_COUNT=$shards SLURM_ARRAY_TASK_MIN=0 \
        SLURM_ARRAY_TASK_MAX=$((shards - 1)) SHARDS=$shards OUT=$out SPLATFFD=$splatffd \
        timeout 300 "$template" "$@" > "$tmp/local-$k.out" 2>&1 &
      pids+=($!)
    done
    for k in "${!pids[@]}"; do wait "${pids[$k]}" || { cat "$tmp/local-$k.out" >&2; fail "shard $k exited non-zero"; }; done
  fi
}

# Renders CLIP as one process and as the array, then checks and compares every frame file.
check_clip() {  # NAME SCENE OPTIONS...
  local name=$1
  shift
  local single=$tmp/$name/single farm=$tmp/$name/farm
  "$splatffd" render "$@" --out "$single" 2> "$tmp/$name.single.log" ||
    { cat "$tmp/$name.single.log" >&2; fail "$name: single-machine render failed"; }
  run_array "$farm" "$@"
  "$splatffd" assemble "$farm" || fail "$name: assemble refused the shards"
  local n=0 f
  for f in "$single"/frame_*; do
    cmp -s "$f" "$farm/$(basename "$f")" || fail "$name: $(basename "$f") differs between the farm and the single render"
    n=$((n + 1))
  done
  [[ $n -gt 0 ]] || fail "$name: the single render wrote no frames"
  local farm_frames
  farm_frames=$(find "$farm" -name 'frame_*' | wc -l)
  [[ $farm_frames == "$n" ]] || fail "$name: the farm wrote $farm_frames frame files, the single render $n"
  grep -q '"state": "complete"' "$farm/render_manifest.json" || fail "$name: the assembled manifest is not complete"
  echo "farm_test: $name: $n frame files identical to the single-machine render"
}

if start_slurm; then
  mode=slurm
  echo "farm_test: running on a single-node Slurm ($(sinfo -h -o '%P %D %t' | head -n 1))"
else
  [[ ${SFFD_REQUIRE_SLURM:-0} == 1 ]] && fail "Slurm could not be started and SFFD_REQUIRE_SLURM=1"
  mode=local
  echo "farm_test: Slurm cannot run here (reason above); running the array's $shards tasks as local processes instead"
fi

# The sphere's built-in clip animates the lattice, so the shards' frames differ in content.
check_clip sphere sphere --frames 0:7 --size 96x54 --format png,exr
# A Gaussian cloud (the sphere converted), orbited: the camera changes every frame.
"$splatffd" convert sphere "$tmp/gaussians.ply" --gaussians > "$tmp/convert.log" 2>&1 ||
  { cat "$tmp/convert.log" >&2; fail "convert --gaussians failed"; }
check_clip gaussians "$tmp/gaussians.ply" --turntable 8 --size 96x54 --format png
echo "farm_test: PASS ($mode)"
