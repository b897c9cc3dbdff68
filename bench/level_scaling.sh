#!/usr/bin/env bash
# The level-sized bake across ranks: hemi-bench's large level (8 x 5 rooms and corridors, 4096^2 atlas,
# 11.9 M covered texels; samples::make_large_level) baked by hemi-bake under a uniform sky and a sun, 2
# bounces, 64 rays per texel, by 1 rank of 1 thread and by 2 ranks of 1 thread each (Open MPI, each rank
# bound to one core), on one machine. Prints each run's wall time, pass time and peak memory, checks that the
# two assets are the same bytes, and prints the parallel efficiency t(1 rank) / (2 t(2 ranks)).
#
#   bench/level_scaling.sh [BUILD_DIR [OUT_DIR]]     (defaults: build/release, /tmp/hemi_level_scaling)
#
# Needs a build with MPI (HEMI_HAS_MPI), mpirun, GNU time (/usr/bin/time) and about 2 x 6 GiB of memory;
# takes about 15 minutes on 2 cores. Run it on a quiet machine: docs/distributed.md quotes its figures.
# HEMI_BENCH_SMOKE=1: the smoke size (2 x 2 rooms, 256^2), seconds, to try the script.
set -euo pipefail
build=${1:-build/release}
out=${2:-/tmp/hemi_level_scaling}
mkdir -p "$out"
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_btl=self,vader
"$build/bench/hemi-bench" --write-large-level="$out/large.glb"
# No checkpoints (an interval of 1e9 s): at this size each one writes 3.9 GB (325 bytes a texel), and only
# rank 0 writes them.
# The sun of hemi-bench's lightmap/bake benchmarks: (0.4, 1, 0.35) in the level's y-up space, world z up.
size=4096
if [ -n "${HEMI_BENCH_SMOKE:-}" ] && [ "${HEMI_BENCH_SMOKE}" != 0 ]; then size=256; fi
bake=(lightmap "$out/large.glb" --size ${size}x${size} --rays 64 --bounces 2 --sun 0.4,-0.35,1,6,6,6
      --checkpoint-interval 1e9)
for np in 1 2; do
    rm -f "$out/np$np.hemi"
    echo "baking with $np rank(s) of 1 thread (log: $out/np$np.log)"
    start=$(date +%s.%N)
    /usr/bin/time -f "%M" -o "$out/np$np.rss" \
        mpirun -np "$np" --bind-to core "$build/baker/hemi-bake" "${bake[@]}" -o "$out/np$np.hemi" \
        --json "$out/np$np.json" > "$out/np$np.log" 2>&1
    end=$(date +%s.%N)
    echo "$start $end" > "$out/np$np.wall"
done
cmp "$out/np1.hemi" "$out/np2.hemi"
/usr/bin/python3 - "$out" <<'EOF'
import json, sys
out = sys.argv[1]
wall, passes = {}, {}
for np in (1, 2):
    start, end = map(float, open(f"{out}/np{np}.wall").read().split())
    wall[np] = end - start
    j = json.load(open(f"{out}/np{np}.json"))
    passes[np] = j["trace_seconds"]
    # GNU time's %M: the largest resident set of mpirun's children, in KiB (one rank's, not the sum).
    rss = int(open(f"{out}/np{np}.rss").read().split()[-1]) / 1024
    print(f"{np} rank(s) x 1 thread: {wall[np]:.1f} s wall, passes {passes[np]:.1f} s, "
          f"{j['covered_texels']} texels, largest rank {rss:.0f} MiB")
print(f"same bytes; parallel efficiency {wall[1] / (2 * wall[2]):.3f} in wall time, "
      f"{passes[1] / (2 * passes[2]):.3f} in the passes")
EOF
