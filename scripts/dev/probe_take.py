# One shape at a time: a Live Link Face CSV in which each ARKit shape alone ramps to a height
# (10 frames), holds (15), ramps back (10) and rests (35), the head and eyes still -- and,
# after `visage eval expressions` has replayed it, what the pipeline read at each hold: the
# shape's own weight and the others that rose with it (docs/performance.md, "the landmark
# network's own response").
#
#   python3 scripts/dev/probe_take.py write OUT.csv [HEIGHT]
#   visage eval expressions OUT.csv --model FaceXModel --out RUN --yaw 0 --pitch 0 --roll 0 --shift 0 --depth-shift 0
#   python3 scripts/dev/probe_take.py read RUN/curves/OUT.csv
import csv, os, sys

shared = os.path.join(os.path.dirname(__file__), '..', '..', '..', 'shared')


def write(out, height):
    header = open(os.path.join(shared, 'data/arkit-takes/alex_rom_4.csv')).readline().strip().split(',')
    names, rest = header[2:2 + 52], header[2 + 52:]
    rows = [{} for _ in range(60)]
    for name in names:
        # mouthClose alone is lips pressed through closed lips; tongueOut has no shape.
        if name in ('MouthClose', 'TongueOut'):
            continue
        rows += [{name: height * (k + 1) / 10} for k in range(10)]
        rows += [{name: height} for _ in range(15)]
        rows += [{name: height * (9 - k) / 10} for k in range(10)]
        rows += [{} for _ in range(35)]
    with open(out, 'w') as f:
        f.write(','.join(header) + '\n')
        for i, w in enumerate(rows):
            timecode = '00:%02d:%02d:%02d.000' % (i // 3600, (i // 60) % 60, i % 60)
            values = ['%.4f' % w.get(n, 0.0) for n in names] + ['0'] * len(rest)
            f.write(timecode + ',61,' + ','.join(values) + '\n')


def read(path):
    rows = list(csv.DictReader(open(path)))
    shapes = [c[len('played_'):] for c in rows[0] if c.startswith('played_') and c[7:] not in ('yaw', 'pitch', 'roll')]
    print('%-20s %5s | %s' % ('played', 'read', 'others read at the hold (> 0.08)'))
    for s in shapes:
        top = max(float(r['played_' + s]) for r in rows)
        hold = [r for r in rows if top > 0 and float(r['played_' + s]) >= 0.9 * top]
        if not hold:
            continue
        mean = {t: sum(float(r['read_' + t]) for r in hold) / len(hold) for t in shapes}
        others = sorted(((v, t) for t, v in mean.items() if t != s and v > 0.08), reverse=True)[:4]
        print('%-20s %5.2f | %s' % (s, mean[s], ' '.join('%s %.2f' % (t, v) for v, t in others)))


if __name__ == '__main__':
    if len(sys.argv) >= 3 and sys.argv[1] == 'write':
        write(sys.argv[2], float(sys.argv[3]) if len(sys.argv) > 3 else 1.0)
    elif len(sys.argv) == 3 and sys.argv[1] == 'read':
        read(sys.argv[2])
    else:
        sys.exit('usage: probe_take.py write OUT.csv [HEIGHT] | read RUN/curves/TAKE.csv')
