# Per frame eye apertures (upper to lower lid centre over the corners) from MediaPipe FaceMesh
# with refine_landmarks=True (its attention mesh lids), as CSV on stdout: frame,mp_r,mp_l.
import sys, csv, cv2, mediapipe as mp
video = sys.argv[1]
fm = mp.solutions.face_mesh.FaceMesh(static_image_mode=False, max_num_faces=1, refine_landmarks=True)
cap = cv2.VideoCapture(video)
w = csv.writer(sys.stdout); w.writerow(["frame", "mp_r", "mp_l"])
i = 0
while True:
    ok, img = cap.read()
    if not ok: break
    r = fm.process(cv2.cvtColor(img, cv2.COLOR_BGR2RGB))
    if r.multi_face_landmarks:
        p = r.multi_face_landmarks[0].landmark
        H, W = img.shape[:2]
        d = lambda a, b: ((p[a].x - p[b].x) * W) ** 2 + ((p[a].y - p[b].y) * H) ** 2
        ap = lambda u, l, a, b: (d(u, l) / d(a, b)) ** 0.5
        w.writerow([i, round(ap(159, 145, 33, 133), 4), round(ap(386, 374, 362, 263), 4)])
    else:
        w.writerow([i, "", ""])
    i += 1
