#!/usr/bin/env bash
# Run one usharp job so that a scheduler may stop it and start it again: the command runs with
# --auto-resume (a fresh start, or the continuation of the journal in its output folder), a
# TERM sent to this script (SLURM's --signal=B:TERM@..., PBS's qdel, a wall-time limit) is
# passed on to usharp, which ends after the evaluation under way (a fit: noted in fit.log; a
# design, self-check or diagnosis: after the task or optimisation under way), and
# the job is then put back in the queue when the scheduler can (USHARP_REQUEUE).
#
# usage: usharp-job.sh INPUT.nml [OUT_DIR]
#        usharp-job.sh [MATRIX.nml] [OUT_DIR]    (USHARP_COMMAND='diagnose --selfcheck': without a
#                                                 matrix, or with '' for it, the built-in one)
# environment:
#   USHARP          the usharp executable (default: usharp on PATH)
#   USHARP_COMMAND  the command: run (default), design, diagnose or 'diagnose --selfcheck'
#                   (each keeps a journal in its output folder and resumes from it)
#   USHARP_THREADS  OpenMP threads per rank (default: the allocation's CPUs per task, else all cores)
#   USHARP_LAUNCHER the MPI launcher and its options for a run over ranks (e.g. 'srun' or
#                   'mpirun -np 16'; default: none, one process)
#   USHARP_REQUEUE  a command that puts this job back in the queue after a stop by TERM that
#                   left work to continue (usharp exit 128 + N; not after exit 0 or a failure)
#                   (the SLURM and PBS scripts set it; empty: none)
set -uo pipefail
input=${1:-}
out=${2:-}
usharp=${USHARP:-usharp}
command=${USHARP_COMMAND:-run}
case " $command " in
  *" --selfcheck "*) ;;
  *) [ -n "$input" ] || { echo "usage: usharp-job.sh INPUT.nml [OUT_DIR]" >&2; exit 2; } ;;
esac

# Threads from the allocation; passive waiting, so that threads that wait give their core away
# on a node shared with other jobs instead of spinning on it
threads=${USHARP_THREADS:-${SLURM_CPUS_PER_TASK:-${PBS_NCPUS:-${NCPUS:-$(nproc)}}}}
export OMP_NUM_THREADS=$threads
export OMP_WAIT_POLICY=${OMP_WAIT_POLICY:-passive}
export OMP_PROC_BIND=${OMP_PROC_BIND:-false}

read -r -a args <<< "$command"
args+=(--auto-resume -q)
[ -n "$out" ] && args+=(-o "$out")
[ -n "$input" ] && args+=("$input")

read -r -a launcher <<< "${USHARP_LAUNCHER:-}"
echo "usharp-job: $(date -u +%FT%TZ) start: ${launcher[*]} $usharp ${args[*]} ($threads threads)" >&2
# The launcher (srun, mpirun) passes a TERM on to every rank
"${launcher[@]}" "$usharp" "${args[@]}" &
pid=$!
stopped=0
# Through a launcher the stop goes on as USR1, which usharp takes as TERM: mpirun passes USR1
# to every rank at once (srun too), but holds a TERM back for its kill timeout and then kills
if [ ${#launcher[@]} -gt 0 ]; then stop_sig=USR1; else stop_sig=TERM; fi
trap 'stopped=1; kill -"$stop_sig" "$pid" 2>/dev/null' TERM INT
while true; do
  wait "$pid"
  rc=$?
  # wait returns early (status > 128) when the trap ran; wait again for usharp itself
  kill -0 "$pid" 2>/dev/null || break
done
if [ "$stopped" -eq 1 ]; then
  # Only a stop that left work to continue goes back in the queue: usharp exits 128 + N when a
  # signal ended it with its journal written. A run that finished before the stop took effect
  # (exit 0) has nothing left, and one that failed (an input, a full disk, a held folder) would
  # fail again at every start.
  if [ "$rc" -gt 128 ] && [ "$rc" -lt 160 ]; then
    echo "usharp-job: $(date -u +%FT%TZ) stopped by TERM (usharp exit $rc); the next start resumes" >&2
    if [ -n "${USHARP_REQUEUE:-}" ]; then
      sh -c "$USHARP_REQUEUE" || echo "usharp-job: requeue failed: $USHARP_REQUEUE" >&2
    fi
  elif [ "$rc" -eq 0 ]; then
    echo "usharp-job: $(date -u +%FT%TZ) TERM came as usharp finished (exit 0); not requeued" >&2
  else
    echo "usharp-job: $(date -u +%FT%TZ) TERM sent, usharp failed (exit $rc); not requeued" >&2
  fi
  exit "$rc"
fi
echo "usharp-job: $(date -u +%FT%TZ) end (exit $rc)" >&2
exit "$rc"
