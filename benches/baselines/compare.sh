#!/usr/bin/env bash
# Side-by-side insertion benchmarks on identical scans, in one run on one machine:
# fusemap, a bare C traversal (the practical ceiling), the design document's numpy
# pipeline and OctoMap, all reading the same SCAN2D01 scan files made by the anchors'
# reference script. Then the real-log timings (decode vs map).
#
#   benches/baselines/compare.sh [SHARED_DIR] > table.txt
#
# Needs: python3 with numpy; gcc; for OctoMap, Debian's liboctomap-dev (skipped when
# absent). The shared directory (default ../shared beside the checkout) holds the anchors
# and the datasets.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../.." && pwd)
shared=${1:-$root/../shared}
anchors=$shared/anchors
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

cargo build --release --quiet --manifest-path "$root/Cargo.toml" -p fusemap-cli
fusemap=$root/target/release/fusemap
cc -O3 -march=native -o "$work/bare" "$here/bare_traversal.c" -lm
have_octomap=0
if g++ -O3 -march=native -I"$anchors" -o "$work/octomap" "$anchors/octomap_bench.cpp" -loctomap -loctomath 2>/dev/null; then
  have_octomap=1
fi

echo "# $(date -u +%FT%TZ) on $(nproc) cores: $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs)"
(cd "$work" && python3 "$anchors/seed_reference.py" --world corridor --scans 40 --export a.scan --export-only >/dev/null \
  && python3 "$anchors/seed_reference.py" --world corridor --scans 20000 --export b.scan --export-only >/dev/null \
  && python3 "$anchors/seed_reference.py" --world big --scans 5000 --beams 1081 --export c.scan --export-only >/dev/null)

echo "## fusemap bench (built-in workloads, each in its own process)"
"$fusemap" bench --json
for w in a b c; do
  echo "## workload $w, identical scans"
  "$fusemap" bench --scanfile "$work/$w.scan" --json
  "$work/bare" "$work/$w.scan"
done
echo "## workload c, first 250 scans (the slow systems' sample)"
"$fusemap" bench --scanfile "$work/c.scan" --max-scans 250 --json
(cd "$work" && python3 "$anchors/seed_reference.py" --scanfile c.scan --impl numpy --limit-scans 250 --out none | grep RESULT)
if [ $have_octomap = 1 ]; then
  "$work/octomap" "$work/c.scan" --hit 0.9 --miss 0.4 --max-scans 250 | grep RESULT
else
  echo "OctoMap not installed (apt-get install liboctomap-dev): skipped"
fi

echo "## real logs: read + map (summary.json decode_s / map_s, wall time)"
for f in rosbag1-slam-benchmark/intel.orig.bag freiburg-079/freiburg-079-corrected.log.gz rosbag1-slam-benchmark/fr079.orig.bag; do
  [ -e "$shared/datasets/$f" ] || { echo "$f: absent"; continue; }
  /usr/bin/time -f "$f: %e s wall, %M KiB peak" "$fusemap" map --out "$work/log" "$shared/datasets/$f" >/dev/null
  python3 -c "import json,sys; s=json.load(open(sys.argv[1])); l=s['log']; print(json.dumps({'log': sys.argv[2], 'scans_read': l['scans_read'], 'scans_used': l['scans_used'], 'decode_s': round(l['decode_s'], 3), 'map_s': round(l['map_s'], 3), 'wall_time_s': round(s['wall_time_s'], 3)}))" "$work/log/summary.json" "$f"
done
