#!/usr/bin/env bash
# A single-node Slurm cluster on this machine, from Debian's packages (munge, slurmctld, slurmd),
# for proving profiles/slurm on a real Slurm (tests/test_slurm.py, `python -m pytest -m slurm`).
#
#   bash cluster/slurm-single-node.sh               # install if needed, start, wait for the node to be idle
#   bash cluster/slurm-single-node.sh --accounting  # the same with job accounting: slurmdbd and MariaDB
#   bash cluster/slurm-single-node.sh stop          # stop the Slurm and munge daemons (MariaDB, if
#                                                   # --accounting started it: /etc/init.d/mariadb stop)
#   bash cluster/slurm-single-node.sh status        # the daemons' pids, and sinfo
#
# Run as root. Idempotent: daemons already running are left running (a changed slurm.conf
# restarts slurmctld and slurmd), and a node left down or drained is resumed.
#
# What it sets up, and why:
# - No systemd, no cgroups: the daemons are started directly, processes are tracked with
#   proctrack/linuxproc and tasks are not confined (task/none), which works in a container or a
#   microVM; memory is still a consumable resource (select/cons_tres, CR_Core_Memory), so a job's
#   --mem keeps jobs from overcommitting the node.
# - The node is this machine, with the CPUs and memory `slurmd -C` finds; one partition, `debug`.
# - By default no accounting database (AccountingStorageType=accounting_storage/none): no
#   slurmdbd, no MariaDB. `sacct` then cannot answer ("Slurm accounting storage is disabled"), so
#   the executor plugin must query job states with squeue (`--slurm-status-command squeue`), and
#   squeue lists a finished job only for MinJobAge seconds after it ends: MinJobAge is 3600 here,
#   far above the plugin's status interval. Jobs are submitted with no account, as the plugin
#   does when none is given or found. With --accounting, slurmdbd keeps the jobs in a local
#   MariaDB and sacct answers, as on a production cluster (the plugin's default status query).
set -euo pipefail

CONF_DIR=/etc/slurm
CONF=$CONF_DIR/slurm.conf
LOG_DIR=/var/log/slurm
PARTITION=debug
DB_PASS=gyrocal-single-node   # MariaDB user 'slurm'@'localhost' only; a throwaway test cluster

say() { echo "slurm-single-node: $*" >&2; }

running() {   # running PIDFILE: the pid in the file is alive
    [[ -s $1 ]] && kill -0 "$(cat "$1")" 2>/dev/null
}

stop_daemon() {   # stop_daemon NAME PIDFILE: SIGTERM, then wait for it to go
    if running "$2"; then
        say "stopping $1 ($(cat "$2"))"
        kill "$(cat "$2")"
        for _ in $(seq 50); do running "$2" || return 0; sleep 0.2; done
        say "$1 did not stop in 10 s"
    fi
}

status() {
    for f in /run/munge/munged.pid /run/slurmdbd.pid /run/slurmctld.pid /run/slurmd.pid; do
        if running "$f"; then echo "$(basename "$f" .pid): running, pid $(cat "$f")"; else echo "$(basename "$f" .pid): not running"; fi
    done
    sinfo 2>&1 || true
}

ACCOUNTING=0
case "${1:-start}" in
    stop)
        stop_daemon slurmd /run/slurmd.pid
        stop_daemon slurmctld /run/slurmctld.pid
        stop_daemon slurmdbd /run/slurmdbd.pid
        stop_daemon munged /run/munge/munged.pid
        exit 0 ;;
    status) status; exit 0 ;;
    start) ;;
    --accounting) ACCOUNTING=1 ;;
    *) echo "usage: $0 [start|--accounting|stop|status]" >&2; exit 2 ;;
esac

[[ $(id -u) == 0 ]] || { say "run as root (it installs packages and starts daemons)"; exit 1; }

install_packages() {
    say "installing $* from Debian's packages"
    export DEBIAN_FRONTEND=noninteractive
    apt-get update -qq
    apt-get install -y -qq --no-install-recommends "$@" >/dev/null
}

# 1. Packages.
if ! command -v slurmctld >/dev/null || ! command -v slurmd >/dev/null || ! command -v munged >/dev/null \
        || ! command -v sinfo >/dev/null; then
    install_packages munge slurmctld slurmd slurm-client
fi

# 2. munge: a key, then the daemon.
install -d -o munge -g munge -m 0700 /etc/munge /var/lib/munge /var/log/munge
install -d -o munge -g munge -m 0755 /run/munge
if [[ ! -s /etc/munge/munge.key ]]; then
    say "creating /etc/munge/munge.key"
    dd if=/dev/urandom of=/etc/munge/munge.key bs=1 count=1024 status=none
    chown munge:munge /etc/munge/munge.key
    chmod 0400 /etc/munge/munge.key
fi
if ! running /run/munge/munged.pid; then
    say "starting munged"
    runuser -u munge -- /usr/sbin/munged
fi
for _ in $(seq 50); do munge -n 2>/dev/null | unmunge >/dev/null 2>&1 && break; sleep 0.2; done
munge -n | unmunge >/dev/null || { say "munge does not work: see /var/log/munge/munged.log"; exit 1; }

install -d -m 0755 "$CONF_DIR" "$LOG_DIR" /var/spool/slurmctld /var/spool/slurmd

# 3. Accounting, if asked for: MariaDB (started by its init script: no systemd here), then slurmdbd.
if [[ $ACCOUNTING == 1 ]]; then
    if ! command -v slurmdbd >/dev/null || ! command -v mariadbd >/dev/null; then
        install_packages slurmdbd mariadb-server
    fi
    if ! mariadb -e 'select 1' >/dev/null 2>&1; then
        say "starting MariaDB"
        /etc/init.d/mariadb start >/dev/null
    fi
    mariadb -e "CREATE DATABASE IF NOT EXISTS slurm_acct_db;
                CREATE USER IF NOT EXISTS 'slurm'@'localhost' IDENTIFIED BY '$DB_PASS';
                GRANT ALL ON slurm_acct_db.* TO 'slurm'@'localhost';"
    DBD_CONF=$(mktemp)
    printf '%s\n' \
        "# Written by gyrocal's cluster/slurm-single-node.sh: accounting in a local MariaDB." \
        "AuthType=auth/munge" "DbdHost=localhost" "SlurmUser=root" "PidFile=/run/slurmdbd.pid" \
        "LogFile=$LOG_DIR/slurmdbd.log" "StorageType=accounting_storage/mysql" "StorageHost=localhost" \
        "StorageUser=slurm" "StoragePass=$DB_PASS" "StorageLoc=slurm_acct_db" > "$DBD_CONF"
    install -m 0600 "$DBD_CONF" "$CONF_DIR/slurmdbd.conf"   # slurmdbd refuses a readable one
    rm -f "$DBD_CONF"
    if ! running /run/slurmdbd.pid; then
        say "starting slurmdbd (log: $LOG_DIR/slurmdbd.log)"
        slurmdbd
    fi
    STORAGE=$'AccountingStorageType=accounting_storage/slurmdbd\nAccountingStorageHost=localhost\nJobAcctGatherType=jobacct_gather/linux'
else
    STORAGE=$'AccountingStorageType=accounting_storage/none\nJobAcctGatherType=jobacct_gather/none'
fi

# 4. slurm.conf for this machine.
NODE=$(hostname -s)
read -r CPUS SOCKETS CORES THREADS MEMORY < <(slurmd -C | head -1 | tr ' ' '\n' | awk -F= '
    /^CPUs=/ {c=$2} /^SocketsPerBoard=/ {s=$2} /^CoresPerSocket=/ {k=$2} /^ThreadsPerCore=/ {t=$2}
    /^RealMemory=/ {m=$2} END {print c, s, k, t, m}')
NEW_CONF=$(mktemp)
cat > "$NEW_CONF" <<EOF
# Written by gyrocal's cluster/slurm-single-node.sh: one node, this machine ($NODE).
ClusterName=gyrocal
SlurmctldHost=$NODE
SlurmUser=root
AuthType=auth/munge
CredType=cred/munge
MpiDefault=none
MailProg=/bin/true
SlurmctldPort=6817
SlurmdPort=6818
SlurmctldPidFile=/run/slurmctld.pid
SlurmdPidFile=/run/slurmd.pid
StateSaveLocation=/var/spool/slurmctld
SlurmdSpoolDir=/var/spool/slurmd
SlurmctldLogFile=$LOG_DIR/slurmctld.log
SlurmdLogFile=$LOG_DIR/slurmd.log
# No cgroups and no systemd here.
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
# Accounting (or none: then status through squeue, which keeps finished jobs for MinJobAge s).
$STORAGE
JobCompType=jobcomp/none
MinJobAge=3600
ReturnToService=2
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_Core_Memory
NodeName=$NODE CPUs=$CPUS SocketsPerBoard=$SOCKETS CoresPerSocket=$CORES ThreadsPerCore=$THREADS RealMemory=$MEMORY State=UNKNOWN
PartitionName=$PARTITION Nodes=$NODE Default=YES MaxTime=INFINITE State=UP
EOF
CHANGED=0
if ! cmp -s "$NEW_CONF" "$CONF"; then
    say "writing $CONF ($NODE: $CPUS CPUs, $MEMORY MB)"
    install -m 0644 "$NEW_CONF" "$CONF"
    CHANGED=1
fi
rm -f "$NEW_CONF"
# sacctmgr reads slurm.conf for where slurmdbd is, so this comes after it is written.
if [[ $ACCOUNTING == 1 ]]; then
    for _ in $(seq 30); do sacctmgr -n list cluster >/dev/null 2>&1 && break; sleep 1; done
    sacctmgr -n list cluster >/dev/null || { say "slurmdbd does not answer: see $LOG_DIR/slurmdbd.log"; exit 1; }
    if [[ -z $(sacctmgr -n list cluster gyrocal format=cluster) ]]; then
        say "registering cluster gyrocal with slurmdbd"
        sacctmgr -i add cluster gyrocal >/dev/null
    fi
fi

# 5. The daemons. A changed slurm.conf restarts them (a new accounting type needs a restart);
#    slurmctld keeps its queue in StateSaveLocation across the restart.
if [[ $CHANGED == 1 ]]; then
    stop_daemon slurmd /run/slurmd.pid
    stop_daemon slurmctld /run/slurmctld.pid
fi
if ! running /run/slurmctld.pid; then
    say "starting slurmctld (log: $LOG_DIR/slurmctld.log)"
    slurmctld
fi
if ! running /run/slurmd.pid; then
    say "starting slurmd (log: $LOG_DIR/slurmd.log)"
    slurmd
fi

# 6. Wait for the node to be idle (resume it if a previous run left it down or drained).
state=""
for i in $(seq 60); do
    state=$(sinfo -h -n "$NODE" -o %T 2>/dev/null | head -1 || true)
    case "$state" in
        idle|mixed|allocated)
            say "node $NODE is $state, partition $PARTITION, accounting $([[ $ACCOUNTING == 1 ]] && echo slurmdbd || echo none)"
            sinfo
            exit 0 ;;
        down*|drain*|fail*)
            if (( i % 5 == 1 )); then say "node is $state: resuming"; scontrol update NodeName="$NODE" State=RESUME || true; fi ;;
    esac
    sleep 1
done
say "node $NODE did not become idle in 60 s (state: '${state:-none}'); see $LOG_DIR/slurmctld.log and $LOG_DIR/slurmd.log"
sinfo -N -l || true
exit 1
