"""JawOpen over a video: frames read with OpenCV, one visage call per frame, a plot.

    python jaw_open_opencv.py VIDEO [OUT.png]

Needs opencv-python-headless and matplotlib beside visage (scripts/setup.sh installs them).
"""

import sys

import cv2
import matplotlib.pyplot as plt  # without a display, matplotlib draws into files (Agg)

import visage

video = cv2.VideoCapture(sys.argv[1])
fps = video.get(cv2.CAP_PROP_FPS) or 30.0
rec = visage.Reconstructor()
jaw = []  # one weight per frame, NaN where no face was found
while (bgr := video.read()[1]) is not None:
    r = rec.process(cv2.cvtColor(bgr, cv2.COLOR_BGR2RGB), timestamp_s=len(jaw) / fps)
    jaw.append(r.blendshapes.get("jawOpen", float("nan")))
plt.plot([i / fps for i in range(len(jaw))], jaw)
plt.gca().set(xlabel="time (s)", ylabel="JawOpen", ylim=(0, 1))
plt.savefig(out := sys.argv[2] if len(sys.argv) > 2 else "jaw_open.png", dpi=100)
print(f"{out}: JawOpen over {len(jaw)} frames, {sum(j == j for j in jaw)} with a face")
