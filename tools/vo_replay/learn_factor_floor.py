#!/usr/bin/env python3
"""Learn vo.window_covariance_min_variance_factor by replaying recorded runs.

    tools/vo_replay/learn_factor_floor.py --build build LOG.lcm [LOG.lcm ...]
        [--floors 0,0.6,0.7,0.8,0.9,1.0] [--target-pct 0.5] [--config configs/vo.yaml]

For each candidate floor it writes a copy of the VO config with the key set, replays every
log with vo_replay (the VO library exactly as the process runs it, judged against the
simulator's truth) and counts the accepted updates beyond the 99.7 % NEES bound (20.06).
It also drives tilt_slope as VoEvaluation.VO13_RenderedWorldNotTunedOnIsHonest does
(vo_eval --world tilt_slope --frames 20 --seed 3), whose mean NEES must stay above 3 (a
covariance made too large fails it). It prints one line per floor and the smallest floor
whose share beyond the bound is at most --target-pct and whose tilt_slope NEES is above 3,
or says that none is. Learn on runs that are not the ones the result is judged on.
Standard library only.
"""
import argparse
import os
import re
import subprocess
import sys
import tempfile


def config_with_floor(base_text, floor):
    key = "  window_covariance_min_variance_factor:"
    lines = [l for l in base_text.splitlines() if not l.startswith(key)]
    out = []
    for line in lines:
        out.append(line)
        if line.startswith("  window_covariance_stereo_carry:"):
            out.append("%s %g" % (key, floor))
    return "\n".join(out) + "\n"


def replay(build, log, config):
    r = subprocess.run([os.path.join(build, "bin", "vo_replay"), log, "--config", config],
                       stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True, check=True)
    m = re.search(r"(\d+) accepted updates with truth, (\d+) beyond .* mean NEES ([0-9.]+)", r.stderr)
    if not m:
        raise RuntimeError("%s: no summary from vo_replay: %s" % (log, r.stderr.strip()))
    return int(m.group(1)), int(m.group(2)), float(m.group(3))


def tilt_slope_nees(build, source, config, out_dir):
    r = subprocess.run([os.path.join(build, "bin", "vo_eval"), "--world",
                        os.path.join(source, "configs/worlds/tilt_slope.yaml"), "--frames", "20", "--seed", "3",
                        "--config", config, "--out", out_dir, "--quiet"],
                       stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, check=True)
    m = re.search(r"NEES mean ([0-9.]+)", r.stdout)
    if not m:
        raise RuntimeError("vo_eval printed no NEES: " + r.stdout[-400:])
    return float(m.group(1))


def main():
    source = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("logs", nargs="+")
    ap.add_argument("--build", default=os.path.join(source, "build"))
    ap.add_argument("--config", default=os.path.join(source, "configs/vo.yaml"))
    ap.add_argument("--floors", default="0,0.6,0.7,0.8,0.9,1.0")
    ap.add_argument("--target-pct", type=float, default=0.5)
    a = ap.parse_args()
    base = open(a.config).read()
    chosen = None
    with tempfile.TemporaryDirectory() as tmp:
        print("floor  updates  beyond  beyond_pct  nees_mean  tilt_slope_nees")
        for floor in [float(f) for f in a.floors.split(",")]:
            cfg = os.path.join(tmp, "vo_%g.yaml" % floor)
            with open(cfg, "w") as f:
                f.write(config_with_floor(base, floor))
            n = b = 0
            s = 0.0
            for log in a.logs:
                ni, bi, mi = replay(a.build, log, cfg)
                n, b, s = n + ni, b + bi, s + mi * ni
            tilt = tilt_slope_nees(a.build, source, cfg, os.path.join(tmp, "tilt"))
            pct = 100.0 * b / n if n else 0.0
            print("%5g  %7d  %6d  %10.2f  %9.2f  %15.2f" % (floor, n, b, pct, s / n if n else 0.0, tilt))
            if chosen is None and pct <= a.target_pct and tilt > 3.0:
                chosen = floor
    if chosen is None:
        print("no floor meets both (beyond <= %g %% and tilt_slope NEES > 3)" % a.target_pct)
        return 1
    print("smallest floor meeting both: %g" % chosen)
    return 0


if __name__ == "__main__":
    sys.exit(main())
