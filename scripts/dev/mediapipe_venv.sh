# Sourced by the dev scripts that run MediaPipe: makes the pinned environment under target/
# (PyPI mediapipe==0.10.21) when it is missing and sets $venv to it.
venv=target/mediapipe-venv
if [ ! -x "$venv/bin/python" ] || ! "$venv/bin/python" -c "import mediapipe, cv2" 2>/dev/null; then
  python3 -m venv "$venv"
  "$venv/bin/pip" install -q mediapipe==0.10.21
fi
