# EyeBlink of visage runs (blendshapes.csv) against MediaPipe's refined lids (mediapipe_lids.py):
# usage: compare_lids.py RUN.csv MEDIAPIPE.csv [RUN.csv MEDIAPIPE.csv …]
# Prints the mean EyeBlink at closed frames, its 95th percentile at open ones, the largest eye-rotation
# jump (degrees) within ±2 frames of closed frames and how far the gaze strays during closures.
import csv, sys, math, statistics as st
def load_mp(path):
    rows = {int(r["frame"]): r for r in csv.DictReader(open(path))}
    ok = {i: (float(r["mp_r"]), float(r["mp_l"])) for i, r in rows.items() if r["mp_r"]}
    mr = st.median(v[0] for v in ok.values()); ml = st.median(v[1] for v in ok.values())
    return {i: (v[0] / mr, v[1] / ml) for i, v in ok.items()}
def load_run(path):
    return list(csv.DictReader(open(path)))
def q(v, p):
    v = sorted(v); return v[min(len(v) - 1, int(p * len(v)))]
for run, mp in zip(sys.argv[1::2], sys.argv[2::2]):
    m = load_mp(mp); rows = load_run(run)
    closed = [i for i, (r, l) in m.items() if r < 0.45 and l < 0.45]
    opened = [i for i, (r, l) in m.items() if r > 0.75 and l > 0.75]
    b = lambda i, s: float(rows[i][f"EyeBlink{s}"])
    cl = [ (b(i,"Left")+b(i,"Right"))/2 for i in closed if i < len(rows)]
    op = [ b(i,s) for i in opened if i < len(rows) for s in ("Left","Right")]
    jump = 0
    for i in closed:
        for j in range(max(1, i - 2), min(len(rows), i + 4)):
            for k in ("LeftEyeYaw","LeftEyePitch","RightEyeYaw","RightEyePitch"):
                jump = max(jump, abs(float(rows[j][k]) - float(rows[j-1][k])) * 180 / math.pi)
    runs = []
    for i in sorted(closed):
        if runs and i <= runs[-1][1] + 2: runs[-1][1] = i
        else: runs.append([i, i])
    dev = 0
    g = lambda j, e: (float(rows[j][e+"EyeYaw"]), float(rows[j][e+"EyePitch"]))
    for a, z in runs:
        for e in ("Left", "Right"):
            r0 = g(a - 2, e)
            for j in range(a - 1, z + 1):
                y, p = g(j, e); dev = max(dev, math.hypot(y - r0[0], p - r0[1]) * 180 / math.pi)
    look = max(float(rows[i][f"EyeLook{d}{s}"]) for i in closed for d in ("Down","Up","In","Out") for s in ("Left","Right"))
    print(f"{run}: closed frames {len(closed)} mean EyeBlink {st.mean(cl) if cl else float('nan'):.2f} min {min(cl) if cl else float('nan'):.2f}; open frames {len(opened)} p95 {q(op,0.95):.2f}; gaze jump near closures {jump:.1f} deg; gaze off its pre-blink value during closures {dev:.1f} deg ({len(runs)} closures); max EyeLook at closed {look:.2f}")
