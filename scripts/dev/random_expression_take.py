# A Live Link Face CSV of random sparse expressions, for `visage eval expressions`: shapes
# switched on independently (bumps of random length and height), left and right mostly
# together, gaze glances, blinks every 2-6 s, rest between -- so that what is learned or
# measured on it cannot lean on one performer's co-activation habits (docs/performance.md,
# "Random expressions"). Deterministic for a seed.
#
#   python3 scripts/dev/random_expression_take.py SEED FRAMES OUT.csv   (needs numpy)
import numpy as np, sys
import os
shared = os.path.join(os.path.dirname(__file__), '..', '..', '..', 'shared')
hdr = open(os.path.join(shared, 'data/arkit-takes/alex_rom_4.csv')).readline().strip().split(',')
names = hdr[2:2+52]
seed, frames, out = int(sys.argv[1]), int(sys.argv[2]), sys.argv[3]
rng = np.random.default_rng(seed)
W = np.zeros((frames, 52))
idx = {n: i for i, n in enumerate(names)}
def bump(n):
    L = rng.integers(16, 70); t = np.arange(L); return np.sin(np.pi * t / (L - 1)) ** 2 * 1.0
pairs = {}
# JawLeft/JawRight and MouthLeft/MouthRight are opposite motions, not a pair of sides.
opposite = {'JawLeft', 'MouthLeft'}
for n in names:
    for a, b in (('Left', 'Right'),):
        if n.endswith(a) and n[:-len(a)] + b in idx and n not in opposite: pairs[n] = n[:-len(a)] + b
look = [n for n in names if n.startswith('EyeLook')]
t = 0
while t < frames:
    if rng.random() < 0.35:  # rest
        t += rng.integers(10, 40); continue
    k = rng.choice([1, 1, 2, 2, 3])
    cand = [n for n in names if n not in look and not n.startswith('EyeBlink')
            and (not n.endswith('Right') or n in ('JawRight', 'MouthRight'))]
    for n in rng.choice(cand, size=k, replace=False):
        b = bump(n); h = rng.uniform(0.3, 1.0); s = min(t + rng.integers(0, 10), frames)
        e = min(frames, s + len(b)); seg = b[:e - s] * h
        if n in pairs:
            mode = rng.random()
            if mode < 0.6: tg = [n, pairs[n]]
            elif mode < 0.8: tg = [n]
            else: tg = [pairs[n]]
        else: tg = [n]
        for m in tg: W[s:e, idx[m]] = np.maximum(W[s:e, idx[m]], seg)
    if rng.random() < 0.3:  # a gaze
        d = rng.choice(['Down', 'Up', 'Left', 'Right']); b = bump(d); h = rng.uniform(0.3, 0.9)
        s = t; e = min(frames, s + len(b)); seg = b[:e - s] * h
        if d in ('Down', 'Up'): cols = [f'EyeLook{d}Left', f'EyeLook{d}Right']
        elif d == 'Left': cols = ['EyeLookOutLeft', 'EyeLookInRight']
        else: cols = ['EyeLookInLeft', 'EyeLookOutRight']
        for c in cols: W[s:e, idx[c]] = np.maximum(W[s:e, idx[c]], seg)
    t += rng.integers(20, 60)
# Blinks as people blink: every 2-6 s, both lids, mostly full; some half blinks and winks.
t = rng.integers(0, 60)
while t < frames:
    L = rng.integers(6, 14); b = np.sin(np.pi * np.arange(L) / (L - 1)) ** 2
    h = 1.0 if rng.random() < 0.7 else rng.uniform(0.4, 0.9)
    side = rng.random(); e = min(frames, t + L)
    cols = ['EyeBlinkLeft', 'EyeBlinkRight'] if side < 0.85 else [rng.choice(['EyeBlinkLeft', 'EyeBlinkRight'])]
    for c in cols: W[t:e, idx[c]] = np.maximum(W[t:e, idx[c]], b[:e - t] * h)
    t += rng.integers(60, 180)
W = np.clip(W, 0, 1)
with open(out, 'w') as f:
    f.write(','.join(hdr) + '\n')
    for i in range(frames):
        sec = i // 30; tc = f"10:{sec // 60 % 60:02d}:{sec % 60:02d}:{(i % 30) * 2:02d}.000"
        f.write(tc + ',61,' + ','.join(f'{x:.6f}' for x in W[i]) + ',' + ','.join(['0'] * (len(hdr) - 54)) + '\n')
print(out, 'mean active', (W > 0.05).sum(1).mean(), 'rest frac', ((W > 0.05).sum(1) == 0).mean())
