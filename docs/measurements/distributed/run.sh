#!/usr/bin/env bash
# Merged N workers x P passes against one worker x N*P passes, both methods, scored against the scenes'
# Mitsuba references (docs/distributed.md). Usage: run.sh OUTDIR SEED [SCENE...]
# Each line of OUTDIR/results.jsonl is one `ppm-vk merge --json` record plus the configuration.
set -euo pipefail
root=$(cd "$(dirname "$0")/../../.." && pwd)
bin=${PPM_VK:-$root/target/release/ppm-vk}
out=$1; seed=$2; shift 2
scenes=${*:-cornell-spheres cornell-smooth}
total=${TOTAL_PASSES:-32}
flags="--resolution ${RES:-128x128} --photons-per-pass ${PHOTONS:-50000} --seed $seed"
mkdir -p "$out"
regions_of() { # boxes in the reference's pixels
  case $1 in
    cornell-spheres) echo "--region caustic:250,436,70,40 --region interior:16,16,480,480" ;;
    cornell-smooth) echo "--region interior:8,8,240,240" ;;
  esac
}
ref_of() {
  case $1 in
    cornell-spheres) echo "$root/../shared/reference/cornell-spheres.exr" ;;
    *) echo "$root/scenes/references/$1.exr" ;;
  esac
}
run() { # scene method workers
  local scene=$1 method=$2 n=$3 p=$(( total / $3 )) tag="$1-$2-n$3-s$seed" parts=()
  for ((k = 0; k < n; k++)); do
    "$bin" render "$root/scenes/$scene.toml" $flags --worker $k --of $n --passes $p --method "$method" \
      -o "$out/$tag-w$k.part" --force >/dev/null 2>>"$out/log.txt"
    parts+=("$out/$tag-w$k.part")
  done
  "$bin" merge "${parts[@]}" -o "$out/$tag.exr" --force --reference "$(ref_of "$scene")" $(regions_of "$scene") --json "$out/$tag.json" \
    | tee -a "$out/log.txt"
  python3 -c "import json,sys; r=json.load(open(sys.argv[1])); r.update(scene=sys.argv[2], method=sys.argv[3], workers=int(sys.argv[4]), passes_per_worker=int(sys.argv[5]), seed=int(sys.argv[6])); print(json.dumps(r))" \
    "$out/$tag.json" "$scene" "$method" "$n" "$p" "$seed" >> "$out/results.jsonl"
  rm -f "${parts[@]}"
}
for scene in $scenes; do
  for method in probabilistic independent; do
    for n in 1 2 4 8; do
      run "$scene" "$method" "$n"
    done
  done
done
