#!/usr/bin/env bash
# A one-node Slurm cluster on this machine, for testing the SLURM profile (docs/cluster.md §7).
#
#   tools/slurm_single_node.sh start    # write the configuration, start the daemons, wait for idle
#   tools/slurm_single_node.sh status   # daemons, sinfo, accounting
#   tools/slurm_single_node.sh stop     # stop every daemon this script started
#
# Needs root and the Debian 12 packages (Slurm 22.05):
#   apt-get install -y slurm-wlm munge slurmdbd mariadb-server
# No systemd: the daemons are started directly. State, spool, logs, the MariaDB data directory and
# the pid files live under $TTB_SLURM_STATE (default /var/tmp/ttbpipe-slurm); the configuration
# goes to /etc/slurm/slurm.conf and /etc/slurm/slurmdbd.conf (where the Slurm commands look for
# it, so sbatch/sacct/squeue work from any shell without SLURM_CONF).
#
# Accounting is real: slurmdbd on a private MariaDB (127.0.0.1:$TTB_SLURM_DB_PORT). The executor
# plugin queries job states with sacct by default and checks the account with sacctmgr; with
# AccountingStorageType=accounting_storage/none, sacct of Slurm 22.05 answers nothing useful and
# the plugin's account check fails, so the test cluster has a database, a cluster
# ($TTB_SLURM_CLUSTER), an account ($TTB_SLURM_ACCOUNT) and the current user in it.
# The node is this host with the CPU count and memory `slurmd -C` reports; one partition
# ($TTB_SLURM_PARTITION, default "debug").
set -euo pipefail

STATE=${TTB_SLURM_STATE:-/var/tmp/ttbpipe-slurm}
CLUSTER=${TTB_SLURM_CLUSTER:-ttbtest}
ACCOUNT=${TTB_SLURM_ACCOUNT:-ttbpipe}
PARTITION=${TTB_SLURM_PARTITION:-debug}
DB_PORT=${TTB_SLURM_DB_PORT:-3307}
DB_PASS=${TTB_SLURM_DB_PASS:-ttbpipe-test}
CONF_DIR=/etc/slurm
DB_SOCK=$STATE/run/mysqld.sock
MUNGE_PID=/run/munge/munged.pid   # munged runs as the munge user and writes its pid file there
USER_NAME=$(id -un)
HOST=$(hostname -s)

log() { echo "slurm_single_node: $*" >&2; }
die() { log "$*"; exit 1; }

pid_alive() { [[ -f $1 ]] && kill -0 "$(cat "$1")" 2>/dev/null; }

wait_for() {   # wait_for SECONDS DESCRIPTION COMMAND...
    local limit=$1 what=$2; shift 2
    local t0=$SECONDS
    until "$@" >/dev/null 2>&1; do
        (( SECONDS - t0 < limit )) || die "timed out after ${limit}s waiting for $what"
        sleep 1
    done
}

write_config() {
    mkdir -p "$STATE"/{log,run,spool/ctld,spool/d} "$CONF_DIR"
    local node
    node=$(slurmd -C | head -1)   # NodeName=vm CPUs=2 Boards=1 ... RealMemory=24105
    [[ $node == NodeName=* ]] || die "slurmd -C gave no node line: $node"
    node="NodeName=$HOST ${node#NodeName=* }"
    cat > "$CONF_DIR/slurm.conf" <<EOF
# written by tools/slurm_single_node.sh (ttbpipe test cluster); state under $STATE
ClusterName=$CLUSTER
SlurmctldHost=$HOST
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
StateSaveLocation=$STATE/spool/ctld
SlurmdSpoolDir=$STATE/spool/d
SlurmctldPidFile=$STATE/run/slurmctld.pid
SlurmdPidFile=$STATE/run/slurmd.pid
SlurmctldLogFile=$STATE/log/slurmctld.log
SlurmdLogFile=$STATE/log/slurmd.log
# no cgroup setup in a container: track processes by parent id, no task binding
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
MpiDefault=none
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_Core_Memory
ReturnToService=2
SlurmctldTimeout=60
SlurmdTimeout=60
# finished jobs stay visible to squeue/scontrol for 5 min (the plugin's squeue mode needs >= 120 s)
MinJobAge=300
AccountingStorageType=accounting_storage/slurmdbd
AccountingStorageHost=localhost
AccountingStorageEnforce=associations
JobAcctGatherType=jobacct_gather/linux
JobAcctGatherFrequency=30
JobCompType=jobcomp/none
# sacct shows the --comment the executor plugin sets (rule and wildcards of each job)
AccountingStoreFlags=job_comment
$node State=UNKNOWN
PartitionName=$PARTITION Nodes=$HOST Default=YES MaxTime=INFINITE State=UP
EOF
    cat > "$CONF_DIR/slurmdbd.conf" <<EOF
# written by tools/slurm_single_node.sh (ttbpipe test cluster)
AuthType=auth/munge
DbdHost=localhost
SlurmUser=root
PidFile=$STATE/run/slurmdbd.pid
LogFile=$STATE/log/slurmdbd.log
StorageType=accounting_storage/mysql
StorageHost=127.0.0.1
StoragePort=$DB_PORT
StorageUser=slurm
StoragePass=$DB_PASS
StorageLoc=slurm_acct_db
EOF
    chmod 600 "$CONF_DIR/slurmdbd.conf"
}

start_munge() {
    if pid_alive "$MUNGE_PID"; then return; fi
    if [[ ! -s /etc/munge/munge.key ]]; then
        log "creating /etc/munge/munge.key"
        mkdir -p /etc/munge
        dd if=/dev/urandom of=/etc/munge/munge.key bs=1 count=1024 status=none
    fi
    chown munge:munge /etc/munge /etc/munge/munge.key
    chmod 700 /etc/munge; chmod 400 /etc/munge/munge.key
    mkdir -p /run/munge /var/log/munge /var/lib/munge
    chown munge:munge /run/munge /var/log/munge /var/lib/munge
    runuser -u munge -- /usr/sbin/munged --pid-file="$MUNGE_PID" --force
    wait_for 20 munged test -s "$MUNGE_PID"
    wait_for 20 "munge round trip" bash -c 'munge -n | unmunge'
}

start_mariadb() {
    if pid_alive "$STATE/run/mariadb.pid"; then return; fi
    local data=$STATE/mysql fresh=0
    if [[ ! -d $data/mysql ]]; then
        fresh=1
        mkdir -p "$data"; chown mysql:mysql "$data"
        mariadb-install-db --user=mysql --datadir="$data" --auth-root-authentication-method=socket \
            --skip-test-db > "$STATE/log/mariadb-install.log" 2>&1
    fi
    chown mysql:mysql "$STATE/run"
    chmod 755 "$STATE/run"
    setsid /usr/sbin/mariadbd --no-defaults --user=mysql --datadir="$data" --socket="$DB_SOCK" \
        --port="$DB_PORT" --bind-address=127.0.0.1 --pid-file="$STATE/run/mariadb.pid" \
        --log-error="$STATE/log/mariadb.log" --innodb-buffer-pool-size=64M \
        < /dev/null > /dev/null 2>&1 &
    wait_for 60 MariaDB mariadb --no-defaults --socket="$DB_SOCK" -u root -e 'select 1'
    if (( fresh )); then
        mariadb --no-defaults --socket="$DB_SOCK" -u root <<EOF
CREATE DATABASE IF NOT EXISTS slurm_acct_db;
CREATE USER IF NOT EXISTS 'slurm'@'127.0.0.1' IDENTIFIED BY '$DB_PASS';
CREATE USER IF NOT EXISTS 'slurm'@'localhost' IDENTIFIED BY '$DB_PASS';
GRANT ALL ON slurm_acct_db.* TO 'slurm'@'127.0.0.1';
GRANT ALL ON slurm_acct_db.* TO 'slurm'@'localhost';
FLUSH PRIVILEGES;
EOF
    fi
}

start_slurmdbd() {
    if pid_alive "$STATE/run/slurmdbd.pid"; then return; fi
    /usr/sbin/slurmdbd
    wait_for 60 slurmdbd sacctmgr -n list cluster
    sacctmgr -i -Q add cluster "$CLUSTER" >/dev/null 2>&1 || true
    sacctmgr -i -Q add account "$ACCOUNT" cluster="$CLUSTER" \
        description="ttbpipe test" organization=ttbpipe >/dev/null 2>&1 || true
    sacctmgr -i -Q add user "$USER_NAME" account="$ACCOUNT" cluster="$CLUSTER" \
        defaultaccount="$ACCOUNT" >/dev/null 2>&1 || true
    sacctmgr -n -P list assoc cluster="$CLUSTER" user="$USER_NAME" format=account \
        | grep -qx "$ACCOUNT" || die "sacctmgr: no association $USER_NAME/$ACCOUNT on $CLUSTER"
}

node_idle() { [[ $(sinfo -h -n "$HOST" -o %t 2>/dev/null) == idle ]]; }

start() {
    [[ $(id -u) == 0 ]] || die "run as root (the daemons and /etc/slurm)"
    for exe in slurmd slurmctld slurmdbd munged mariadbd sinfo sacct; do
        command -v "$exe" >/dev/null || [[ -x /usr/sbin/$exe ]] \
            || die "$exe missing: apt-get install -y slurm-wlm munge slurmdbd mariadb-server"
    done
    write_config
    start_munge
    start_mariadb
    start_slurmdbd
    if ! pid_alive "$STATE/run/slurmctld.pid"; then /usr/sbin/slurmctld; fi
    wait_for 60 slurmctld scontrol ping
    if ! pid_alive "$STATE/run/slurmd.pid"; then /usr/sbin/slurmd; fi
    if ! (wait_for 60 "node idle" node_idle) 2>/dev/null; then
        scontrol update nodename="$HOST" state=resume 2>/dev/null || true
        wait_for 30 "node $HOST idle (sinfo)" node_idle
    fi
    log "node $HOST idle in partition $PARTITION, account $ACCOUNT (cluster $CLUSTER)"
    sinfo
}

stop_pid() {   # stop_pid NAME PIDFILE
    local f=$2 pid
    pid_alive "$f" || { rm -f "$f"; return 0; }
    pid=$(cat "$f")
    kill "$pid"
    for _ in $(seq 30); do kill -0 "$pid" 2>/dev/null || break; sleep 1; done
    if kill -0 "$pid" 2>/dev/null; then log "$1 ($pid) still running; SIGKILL"; kill -9 "$pid"; fi
    rm -f "$f"
}

stop() {
    # jobs first, so that no slurmstepd is left behind
    if pid_alive "$STATE/run/slurmctld.pid"; then scancel --quiet --user="$USER_NAME" || true; fi
    stop_pid slurmd "$STATE/run/slurmd.pid"
    stop_pid slurmctld "$STATE/run/slurmctld.pid"
    stop_pid slurmdbd "$STATE/run/slurmdbd.pid"
    stop_pid mariadbd "$STATE/run/mariadb.pid"
    stop_pid munged "$MUNGE_PID"
    log "stopped (state kept in $STATE; remove it for a fresh cluster)"
}

status() {
    local name rc=0
    for name in munged mariadb slurmdbd slurmctld slurmd; do
        local f=$STATE/run/$name.pid
        [[ $name == munged ]] && f=$MUNGE_PID
        if pid_alive "$f"; then
            echo "$name: running (pid $(cat "$f"))"
        else
            echo "$name: stopped"; rc=1
        fi
    done
    if (( rc == 0 )); then sinfo; sacctmgr -n list assoc format=cluster,account,user; fi
    return $rc
}

case ${1:-} in
    start) start ;;
    stop) stop ;;
    status) status ;;
    *) echo "usage: $0 start|stop|status" >&2; exit 2 ;;
esac
