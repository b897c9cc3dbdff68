#!/usr/bin/env bash
# Issue 45's out-of-core bake: hemi-bench's large level (8 x 5 rooms and corridors; samples::make_large_level)
# with its lightmap UVs baked into an 11904^2 atlas, about 10^8 covered texels, under --memory-budget 2G:
# in tiles, the passes' sums in the tile file, the atlas's records in pages of files. A uniform sky and the
# sun of hemi-bench's lightmap benchmarks, 1 bounce, 4 rays per texel, the plain output. Prints the wall
# time, the peak memory (the process's high-water mark), the most disk the bake's files took at once (its
# output folder, sampled every 2 s) and the JSON's summary.
#
#   bench/out_of_core.sh [BUILD_DIR [OUT_DIR [SIZE]]]   (defaults: build/release, /tmp/hemi_out_of_core, 11904)
#
# Needs GNU time (/usr/bin/time) and about 40 GB of disk in OUT_DIR; takes about half an hour on 2 cores.
# SIZE 2048 tries it in a minute.
set -euo pipefail
build=${1:-build/release}
out=${2:-/tmp/hemi_out_of_core}
size=${3:-11904}
mkdir -p "$out"
rm -f "$out/level.hemi" "$out/level.json"
"$build/bench/hemi-bench" --write-large-level="$out/level.glb"
# The sun of hemi-bench's lightmap/bake benchmarks: (0.4, 1, 0.35) in the level's y-up space, world z up.
bake=(lightmap "$out/level.glb" --size "$size" --rays 4 --bounces 1 --bases plain --sun 0.4,-0.35,1,6,6,6
      --memory-budget 2G --checkpoint-interval 1e9 -o "$out/level.hemi" --json "$out/level.json")
echo "hemi-bake ${bake[*]}"
start=$(date +%s.%N)
/usr/bin/time -f "%M" -o "$out/rss" "$build/baker/hemi-bake" "${bake[@]}" > "$out/log" 2>&1 &
pid=$!
most=0
while kill -0 "$pid" 2> /dev/null; do
    used=$(du -sk "$out" | cut -f1)
    [ "$used" -gt "$most" ] && most=$used
    sleep 2
done
wait "$pid"
end=$(date +%s.%N)
/usr/bin/python3 - "$out" "$start" "$end" "$most" <<'PY'
import json, sys
out, start, end, most = sys.argv[1], float(sys.argv[2]), float(sys.argv[3]), int(sys.argv[4])
j = json.load(open(out + "/level.json"))
rss = int(open(out + "/rss").read().split()[-1]) * 1024
print(f"{j['covered_texels']} covered texels, {j['tiles_per_pass']} tiles of {j['tile_texels']} texels a pass, "
      f"records in pages: {j['paged_records']}, rasteriser bands of {j['raster_band_slots']} slots")
print(f"wall {end - start:.0f} s; peak {rss / 2**30:.2f} GiB (JSON: {j['peak_memory_bytes'] / 2**30:.2f} GiB) "
      f"under a budget of {j['memory_budget_bytes'] / 2**30:.2f} GiB; most disk {most / 2**20:.1f} GiB")
print("stages: " + ", ".join(f"{name} {s:.0f} s" for name, s in j["stage_seconds"].items()))
PY
