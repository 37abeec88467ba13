#!/bin/bash
# Submits the sweep's job array, then the merge, which starts only if every task succeeded.
set -euo pipefail
array=$(sbatch --parsable slurm-sweep.sbatch)
sbatch --wait --dependency=afterok:${array} --output=merge-%j.log \
    --wrap 'stickslip merge --out all.jsonl --total 111 part-*.jsonl'
