#!/bin/sh
# The cloud lighting fit's benchmark (issue 11): one cloudy 512x256 reference rendered from
# the bundled cloudy preset (sky + HZD clouds, Vulkan), fitted with --clouds on, once from
# the bundled clear preset (relative) and once from the cloudy preset's sky (--absolute:
# the truth is known). Prints wall and CPU time of each whole process and the fit.json
# clouds.solve record. Usage: bench/fit_clouds.sh [BUILD_DIR] (default build).
set -eu
B=${1:-build}
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
P=datasets/presets/default_cloudy.json
"$B/skycal" render --preset $P --clouds --sun-elevation 30 --sun-azimuth 40 --size 512x256 --out "$T/cloudy.exr" >/dev/null 2>&1
for mode in relative absolute; do
  extra=""
  [ $mode = absolute ] && extra="--init $P --absolute"
  # Wall and CPU time of the whole process (python3's resource module: no /usr/bin/time needed).
  python3 - "$mode" "$B/skycal" fit --reference "$T/cloudy.exr" --clouds on --cloud-preset $P $extra --quiet \
    --out "$T/fit_$mode" <<'PY'
import resource, subprocess, sys, time
t0 = time.time()
subprocess.run(sys.argv[2:], check=True, stderr=subprocess.DEVNULL)
r = resource.getrusage(resource.RUSAGE_CHILDREN)
print("%s: wall %.2f s, user %.2f s, sys %.2f s" % (sys.argv[1], time.time() - t0, r.ru_utime, r.ru_stime))
PY
  python3 - "$T/fit_$mode/fit.json" <<'PY'
import json, sys
j = json.load(open(sys.argv[1])); c = j["clouds"]
print("  fit.json time_s %.2f (now the whole fit, sky and clouds; before this change the sky fit alone), levels %s" % (j["time_s"], [(l["iterations"], l["renders"]) for l in j["levels"]]))
print("  clouds.solve", json.dumps(c["solve"]))
print("  cloud pixels", c["cloud_pixels"]["count"], "samples", c["cloud_pixels"]["samples"],
      "log RMSE initial %.5f final %.5f, clear %.5f, whole-sky rel RMSE %.5f" % (
      c["cloud_pixels"]["initial"]["log_rmse"], c["cloud_pixels"]["final"]["log_rmse"], c["clear_pixels"]["log_rmse"],
      j["references"][0]["rel_rmse"]))
for k, v in c["parameters"].items():
    print("   %-20s %-5s initial %-8.5g fitted %-10.6g held %-5s predicted %s" % (k, v["unit"], v["initial"], v["value"], v["held"], v.get("predicted_relative_error")))
print("  singular values", ["%.3g" % s for s in c["singular_values"]])
PY
done
