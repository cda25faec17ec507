#!/usr/bin/env bash
# A shelfcross campaign across several hosts with Open MPI: rank 0 (on the first host)
# coordinates and writes the one results database; every other rank runs simulations on
# --jobs threads.
#
#   scripts/mpi_campaign.sh HOSTFILE --runs R --out DIR [more `shelfcross campaign` options]
#
# HOSTFILE lists the hosts, one per line, with how many ranks each takes, e.g.
#     node01 slots=1        # rank 0, the coordinator: little work, any host will do
#     node02 slots=1
#     node03 slots=1
# Every host needs the same build of shelfcross at the same path (a shared file system or
# the same install), password-less ssh from the first host, and Open MPI (openmpi-bin).
# Run workers one rank per host with --jobs = its cores (each thread runs whole simulations).
# Inside a Slurm allocation (salloc/sbatch -N ...), drop the hostfile: mpirun takes the
# allocation's nodes. The same command again resumes; `mpirun --enable-recovery` (added below)
# lets the campaign go on when a worker host dies (docs/campaigns.md).
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
program="${SHELFCROSS:-$here/build/release/app/shelfcross}"
hostfile="$1"
shift
ranks=$(awk '!/^[[:space:]]*(#|$)/ { n = 1; for (i = 2; i <= NF; ++i) if ($i ~ /^slots=/) { sub("slots=", "", $i); n = $i } s += n } END { print s }' "$hostfile")
exec mpirun --hostfile "$hostfile" -np "$ranks" --map-by slot --bind-to none --enable-recovery \
  "$program" campaign "$@"
