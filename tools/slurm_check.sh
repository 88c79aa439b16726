#!/usr/bin/env bash
# End-to-end check of the SLURM profile and of Dask on SLURM against a local run (docs/cluster.md §7).
#
#   tools/slurm_check.sh            # as root, from anywhere; exit status 0 only if all match
#
# 1. starts the one-node test cluster (tools/slurm_single_node.sh; stopped again at the end
#    unless it was already running),
# 2. runs the small study tests/cluster/small_study.yaml three times, each in its own scratch copy
#    of this checkout under $CHECK_DIR:
#      local/  snakemake --cores 2 (the default workflow profile),
#      slurm/  snakemake --profile profiles/slurm (the shipped profile plus the test cluster's
#              account and partition and a short first status check, written to
#              profiles/slurm-test/config.yaml of the copy),
#      dask/   snakemake --cores 2 with simulation.executor: dask, the batches sent to a
#              dask_jobqueue.SLURMCluster of $DASK_WORKERS one-core worker jobs
#              (tools/dask_slurm_cluster.py),
# 3. compares slurm/ and dask/ with local/ bit for bit (tools/compare_results.py: every file under
#    results/; Parquet by schema, values and provenance without its write time; the Dask run also
#    without the provenance's simulation.executor and simulation.dask (the batch records
#    local_workers = its Snakemake threads) and without the report page that renders the
#    configuration, study/report/configuration.html), and checks with sacct that the SLURM run's
#    jobs and the Dask worker jobs ran on the cluster and completed,
# 4. prints the wall times and the job counts, and writes them to $CHECK_DIR/summary.txt.
#
# Environment: PYTHON (default /work/venv-slurm/bin/python: an environment with this checkout
# installed, `pip install -c requirements.lock.txt -e ".[test,cluster]"`), CHECK_DIR (default
# /var/tmp/ttbpipe-slurm-check), DASK_WORKERS (2), and the cluster's TTB_SLURM_* variables.
set -euo pipefail

REPO=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
PYTHON=${PYTHON:-/work/venv-slurm/bin/python}
CHECK_DIR=${CHECK_DIR:-/var/tmp/ttbpipe-slurm-check}
ACCOUNT=${TTB_SLURM_ACCOUNT:-ttbpipe}
PARTITION=${TTB_SLURM_PARTITION:-debug}
DASK_WORKERS=${DASK_WORKERS:-2}
STUDY=tests/cluster/small_study.yaml
CLUSTER_SH=$REPO/tools/slurm_single_node.sh
export TTB_SLURM_ACCOUNT=$ACCOUNT TTB_SLURM_PARTITION=$PARTITION

log() { echo "slurm_check: $*" >&2; }
die() { log "FAIL: $*"; exit 1; }

"$PYTHON" -c "import ttbpipe, snakemake, snakemake_executor_plugin_slurm, dask_jobqueue" \
    || die "$PYTHON lacks ttbpipe, snakemake, the SLURM plugin or dask-jobqueue: pip install -c requirements.lock.txt -e \"$REPO[test,cluster]\""
# the SLURM job scripts re-run Snakemake with this interpreter (sys.executable, sbatch
# --export=ALL); the environment first on PATH also for anything the rules call by name
export PATH="$(dirname "$PYTHON"):$PATH"

started_cluster=0
dask_pid=
cleanup() {
    local rc=$?
    if [[ -n $dask_pid ]] && kill -0 "$dask_pid" 2>/dev/null; then
        kill "$dask_pid"; wait "$dask_pid" 2>/dev/null || true
    fi
    if (( started_cluster )); then "$CLUSTER_SH" stop || true; fi
    exit $rc
}
trap cleanup EXIT

if ! "$CLUSTER_SH" status >/dev/null 2>&1; then
    started_cluster=1
    "$CLUSTER_SH" start
fi

copy_checkout() {   # copy_checkout DEST: the tracked and untracked-unignored files, as tests/test_workflow.py
    local dest=$1 name
    rm -rf "$dest"; mkdir -p "$dest/resources/inspections"
    (cd "$REPO" && git ls-files -co --exclude-standard) | while read -r name; do
        case $name in results/*|resources/inspections/*|.*) continue ;; esac
        [[ -f $REPO/$name && ! -L $REPO/$name ]] || continue
        mkdir -p "$dest/$(dirname "$name")"
        cp -p "$REPO/$name" "$dest/$name"
    done
    ln -s workflow/profiles "$dest/profiles"
}

now() { date +%s.%N; }
elapsed() { "$PYTHON" -c "import sys; print(f'{float(sys.argv[2]) - float(sys.argv[1]):.0f}')" "$1" "$2"; }

mkdir -p "$CHECK_DIR"
SUMMARY=$CHECK_DIR/summary.txt
: > "$SUMMARY"
record() { echo "$*" | tee -a "$SUMMARY"; }
record "slurm_check $(date -u +%FT%TZ) on $(hostname -s) ($(env -u OMP_NUM_THREADS -u OMP_THREAD_LIMIT nproc) CPUs), $(sinfo --version), code $(cd "$REPO" && git rev-parse --short HEAD)$(cd "$REPO" && git diff --quiet HEAD || echo '+dirty')"

# --- 1. local reference ------------------------------------------------------------------------
copy_checkout "$CHECK_DIR/local"
t0=$(now)
(cd "$CHECK_DIR/local" && "$PYTHON" -m snakemake --cores 2 --configfile "$STUDY") \
    > "$CHECK_DIR/local.log" 2>&1 || { tail -40 "$CHECK_DIR/local.log"; die "local run failed"; }
t_local=$(elapsed "$t0" "$(now)")
n_local=$(grep -Eo '^[0-9]+ of [0-9]+ steps \(100%\) done' "$CHECK_DIR/local.log" | tail -1)
record "local: ${t_local} s, ${n_local}"

# --- 2. SLURM profile --------------------------------------------------------------------------
copy_checkout "$CHECK_DIR/slurm"
# the shipped profile with the test cluster's account and partition in default-resources (on the
# command line, --default-resources would replace the profile's whole default-resources list) and
# the first status check after 5 s instead of 40 (short jobs); at most one status query a second
"$PYTHON" - "$CHECK_DIR/slurm/workflow/profiles" "$ACCOUNT" "$PARTITION" <<'EOF'
import sys, pathlib, yaml
root, account, partition = pathlib.Path(sys.argv[1]), sys.argv[2], sys.argv[3]
profile = yaml.safe_load((root / "slurm" / "config.yaml").read_text())
profile["default-resources"] = {"slurm_account": account, "slurm_partition": partition,
                                **profile["default-resources"]}
profile["slurm-init-seconds-before-status-checks"] = 5
profile["max-status-checks-per-second"] = 1
(root / "slurm-test").mkdir()
(root / "slurm-test" / "config.yaml").write_text(yaml.safe_dump(profile, sort_keys=False))
EOF
t0=$(now); sacct_start=$(date +%FT%T)
(cd "$CHECK_DIR/slurm" && "$PYTHON" -m snakemake --profile profiles/slurm-test --configfile "$STUDY") \
    > "$CHECK_DIR/slurm.log" 2>&1 || { tail -60 "$CHECK_DIR/slurm.log"; die "SLURM run failed"; }
t_slurm=$(elapsed "$t0" "$(now)")
sleep 2
n_slurm=$(grep -Eo '^[0-9]+ of [0-9]+ steps \(100%\) done' "$CHECK_DIR/slurm.log" | tail -1)
sacct -X -n -P -S "$sacct_start" -E now --format=JobID,JobName,State,Elapsed,ReqMem,Timelimit,Comment \
    > "$CHECK_DIR/slurm.sacct"
n_sbatch=$(grep -c "Job .* has been submitted with SLURM jobid" "$CHECK_DIR/slurm.log" || true)
n_jobs=$(wc -l < "$CHECK_DIR/slurm.sacct")
n_done=$(grep -c '|COMPLETED|' "$CHECK_DIR/slurm.sacct" || true)
record "slurm: ${t_slurm} s, ${n_slurm}; sacct: ${n_jobs} jobs, ${n_done} COMPLETED; sbatch submissions in the Snakemake log: ${n_sbatch}"
record "slurm jobs per rule (sacct Comment): $(cut -d'|' -f7 "$CHECK_DIR/slurm.sacct" | sed -E 's/^rule_([a-z0-9_]+)_wildcards.*$/\1/; s/^rule_([a-z0-9_]+)$/\1/' | sort | uniq -c | awk '{printf "%s%s %s", (NR > 1 ? ", " : ""), $2, $1}')"
(( n_jobs > 0 && n_jobs == n_done && n_jobs == n_sbatch )) \
    || die "SLURM jobs: $n_jobs in sacct, $n_done completed, $n_sbatch submitted ($CHECK_DIR/slurm.sacct)"

# --- 3. Dask on SLURM --------------------------------------------------------------------------
copy_checkout "$CHECK_DIR/dask"
printf 'simulation:\n  executor: dask\n' > "$CHECK_DIR/dask/dask_executor.yaml"
addr=$CHECK_DIR/dask/scheduler.address
t0=$(now); sacct_start=$(date +%FT%T)
(cd "$CHECK_DIR/dask" && exec "$PYTHON" "$REPO/tools/dask_slurm_cluster.py" --account "$ACCOUNT" \
    --partition "$PARTITION" --workers "$DASK_WORKERS" --address-file "$addr" \
    --log-directory logs/dask-slurm) > "$CHECK_DIR/dask-cluster.log" 2>&1 &
dask_pid=$!
for _ in $(seq 300); do [[ -s $addr ]] && break; kill -0 $dask_pid 2>/dev/null || break; sleep 1; done
[[ -s $addr ]] || { tail -30 "$CHECK_DIR/dask-cluster.log"; die "the SLURMCluster did not start"; }
t_dask_up=$(elapsed "$t0" "$(now)")
(cd "$CHECK_DIR/dask" && TTBPIPE_DASK_SCHEDULER=$(cat "$addr") "$PYTHON" -m snakemake --cores 2 \
    --configfile "$STUDY" dask_executor.yaml) > "$CHECK_DIR/dask.log" 2>&1 \
    || { tail -60 "$CHECK_DIR/dask.log"; die "Dask run failed"; }
kill "$dask_pid"; wait "$dask_pid" 2>/dev/null || true; dask_pid=
t_dask=$(elapsed "$t0" "$(now)")
sleep 2
n_dask=$(grep -Eo '^[0-9]+ of [0-9]+ steps \(100%\) done' "$CHECK_DIR/dask.log" | tail -1)
sacct -X -n -P -S "$sacct_start" -E now --name=ttbpipe-dask --format=JobID,JobName,State,Elapsed \
    > "$CHECK_DIR/dask.sacct"
n_workers=$(wc -l < "$CHECK_DIR/dask.sacct")
n_batches=$(grep -l "dask: connected to scheduler" -r "$CHECK_DIR/dask/logs/study/batches" | wc -l)
n_batch_jobs=$(grep -Ec "^(local)?rule simulate_batch:" "$CHECK_DIR/dask.log" || true)
record "dask: ${t_dask} s including ${t_dask_up} s to start the SLURMCluster, ${n_dask}; ${n_batches} of ${n_batch_jobs} batch jobs on the cluster; sacct: ${n_workers} worker jobs ($(cut -d'|' -f3 "$CHECK_DIR/dask.sacct" | sort | uniq -c | xargs))"
(( n_workers == DASK_WORKERS && n_batches == n_batch_jobs && n_batches > 0 )) \
    || die "Dask: $n_workers worker jobs (expected $DASK_WORKERS), $n_batches of $n_batch_jobs batches on the cluster"

# --- 4. bit-for-bit comparison -----------------------------------------------------------------
status=0
"$PYTHON" "$REPO/tools/compare_results.py" "$CHECK_DIR/local/results" "$CHECK_DIR/slurm/results" \
    | tee -a "$SUMMARY" || status=1
"$PYTHON" "$REPO/tools/compare_results.py" "$CHECK_DIR/local/results" "$CHECK_DIR/dask/results" \
    --ignore-config-key simulation.executor --ignore-config-key simulation.dask \
    --skip study/report/configuration.html | tee -a "$SUMMARY" || status=1
(( status == 0 )) || die "results differ (above; logs and results in $CHECK_DIR)"
record "slurm_check: OK (summary in $SUMMARY)"
