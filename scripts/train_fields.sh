#!/usr/bin/env bash
# Train the NIF (SCF) and the NDF (occupancy) side by side on the same data, from the shipped
# weights, for the same wall-clock budget: the two fields Table I compares, trained alike.
#   scripts/train_fields.sh DATA TEST OUT MINUTES [more `nift train` options]
# Writes OUT/{nif,ndf}.pt with model cards (.json) and logs (.log). On a GPU both share it; on CPU
# give each `--threads 1`. NIFT overrides the command (e.g. NIFT="python3 -m app.cli").
set -euo pipefail
if [ $# -lt 4 ]; then
  echo "usage: $0 DATA TEST OUT MINUTES [nift train options]" >&2
  exit 2
fi
data=$1 test=$2 out=$3 minutes=$4
shift 4
mkdir -p "$out"
source "$(dirname "$0")/side_by_side.sh"
for name in nif ndf; do
  target=$([ "$name" = nif ] && echo scf || echo occ)
  launch "$out/$name.log" train --target "$target" --data "$data" --eval-data "$test" --out "$out/$name-run" \
    --weights "$out/$name.pt" --init "$name" --minutes "$minutes" --json "$@"
done
status=0
wait_all || status=1
for name in nif ndf; do
  echo "== $name"; tail -n 30 "$out/$name.log"
done
exit $status
