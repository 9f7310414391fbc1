#!/usr/bin/env bash
# Table III's fields: one NIF per SCF order, all fine-tuned from the same weights on the same data
# for the same wall-clock budget, side by side (one GPU shares them; on CPU add `--threads 1`).
#   scripts/train_scf_orders.sh DATA TEST OUT MINUTES INIT "ORDERS" [more `nift train` options]
# e.g. scripts/train_scf_orders.sh data/scf10-train data/scf10-test runs/table3 6 \
#        app/nift/weights/fused/nif.pt "1 3 5 7 10" --lr 5e-4 --lr-final 1e-5 --batch-size 64
# DATA must store bands up to the highest order (`nift make-data --scf-order 10`). Writes
# OUT/nif-N.pt with its model card and OUT/nif-N.log. NIFT overrides the command.
set -euo pipefail
if [ $# -lt 6 ]; then
  echo "usage: $0 DATA TEST OUT MINUTES INIT \"ORDERS\" [nift train options]" >&2
  exit 2
fi
data=$1 test=$2 out=$3 minutes=$4 init=$5 orders=$6
shift 6
mkdir -p "$out"
source "$(dirname "$0")/side_by_side.sh"
for n in $orders; do
  launch "$out/nif-$n.log" train --target scf --scf-order "$n" --data "$data" --eval-data "$test" \
    --out "$out/nif-$n-run" --weights "$out/nif-$n.pt" --init "$init" --minutes "$minutes" --json "$@"
done
status=0
wait_all || status=1
for n in $orders; do
  echo "== order $n"; grep -E '"(steps|scf_r2)":' "$out/nif-$n.log" || tail -n 3 "$out/nif-$n.log"
done
exit $status
