"""visage: metric 3-D face meshes, ARKit blendshapes and head pose from ordinary RGB video, on a CPU.

The Rust library visage as a Python package::

    import visage

    rec = visage.Reconstructor()
    for frame in visage.open("face.mp4"):
        result = rec.process(frame.image, timestamp_s=frame.timestamp_s)
        print(result.status, result.blendshapes.get("jawOpen"), result.head_angles)

- :class:`Reconstructor` processes ``(H, W, 3)`` uint8 RGB frames one at a time (causally: each
  frame's result as soon as it is given), with the GIL released while it works.
- :func:`open` reads a video, an image folder or an image as visage does.
- :func:`read_run` loads a run folder written by ``visage run`` into numpy.

Coordinates: camera coordinates, x right, y down, z forward, metres; pixel ``(i, j)``'s centre
at ``(i, j)``. Errors from visage are :class:`VisageError`, with the command line's message.
"""

from __future__ import annotations

import csv
import json
import os
import struct
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Dict, Iterator, List, Optional, Tuple, Union

import numpy as np

from ._visage import ARKIT_BLENDSHAPES, NativeFrames, NativeReconstructor, VisageError

__all__ = [
    "ARKIT_BLENDSHAPES",
    "Frame",
    "FrameResult",
    "Reconstructor",
    "RunData",
    "VisageError",
    "open",
    "read_run",
]

PathLike = Union[str, "os.PathLike[str]"]

#: Model files the package needs (MediaPipe's networks and canonical face, Apache-2.0; the wheel
#: carries them in ``visage/models/`` with their ``NOTICE``).
MODEL_FILES = (
    "face_detection_short_range.tflite",
    "face_landmark.tflite",
    "iris_landmark.tflite",
    "geometry_pipeline_metadata_landmarks.binarypb",
)


def _models_dir(models: Optional[PathLike]) -> Optional[str]:
    """Where the model files are: ``models``, else ``$VISAGE_MODELS``, else the wheel's own."""
    if models is not None:
        return os.fspath(models)
    env = os.environ.get("VISAGE_MODELS")
    if env:
        return env
    bundled = Path(__file__).parent / "models"
    if all((bundled / f).is_file() for f in MODEL_FILES):
        return str(bundled)
    return None


@dataclass(frozen=True)
class FrameResult:
    """What :meth:`Reconstructor.process` made of one frame."""

    #: The frame's number (0 for the first frame given to this reconstructor).
    index: int
    #: ``"solved"`` (a mesh fused), ``"carried"`` (the previous surface kept), ``"no_face"``
    #: or ``"no_data"``.
    status: str
    #: The fused metric face mesh ``(V, 3)`` float32, metres, camera coordinates; ``None``
    #: without a mesh. Vertex ``i < 468`` is FaceMesh landmark ``i``.
    vertices: Optional[np.ndarray]
    #: The tracked 468 landmarks ``(468, 2)`` float32, frame pixels; ``None`` without a face.
    landmarks: Optional[np.ndarray]
    #: The 52 ARKit blendshape weights by name (empty without a face).
    blendshapes: Dict[str, float]
    #: The same in ARKit's order (:data:`ARKIT_BLENDSHAPES`), ``(52,)`` float32, or ``None``.
    blendshape_array: Optional[np.ndarray]
    #: Model → camera, ``(4, 4)`` float64 (the metric head pose), or ``None``.
    head_pose: Optional[np.ndarray]
    #: Live Link Face's head ``(yaw, pitch, roll)`` in radians (yaw > 0 turning to the
    #: subject's right, pitch > 0 looking down), or ``None``.
    head_angles: Optional[Tuple[float, float, float]]
    #: The frame's record as ``metrics.json`` has it (stage times in ``metrics["ms"]``).
    metrics: Dict[str, Any] = field(repr=False)

    @property
    def timings_ms(self) -> Dict[str, float]:
        """Milliseconds per stage of this frame."""
        return dict(self.metrics.get("ms", {}))


class Reconstructor:
    """Metric face meshes, blendshapes and head pose from frames, one at a time.

    Args:
        fov_deg: the camera's horizontal field of view in degrees (default: visage's guess,
            as ``visage run`` makes it).
        models: folder of the model files (default: ``$VISAGE_MODELS``, else the wheel's own).

    One reconstructor follows one video: its frames must keep one size. It is causal — each
    frame's result comes at once — and keeps its state (the face's identity, the temporal
    smoothing) from frame to frame. Use one per video, and one per thread.
    """

    def __init__(self, fov_deg: Optional[float] = None, models: Optional[PathLike] = None) -> None:
        self._native = NativeReconstructor(fov_deg, _models_dir(models))

    def process(self, frame: np.ndarray, timestamp_s: Optional[float] = None) -> FrameResult:
        """Processes one frame: an ``(H, W, 3)`` uint8 RGB array (OpenCV's frames are BGR:
        ``frame[:, :, ::-1]``). ``timestamp_s``: its time in seconds, when known."""
        if not isinstance(frame, np.ndarray):
            raise ValueError(f"a frame is an (H, W, 3) uint8 RGB numpy array, not {type(frame).__name__}")
        if frame.dtype != np.uint8:
            raise ValueError(f"a frame is an (H, W, 3) uint8 RGB array; this one's dtype is {frame.dtype}")
        if frame.ndim != 3 or frame.shape[2] != 3:
            raise ValueError(f"a frame is an (H, W, 3) uint8 RGB array; this one's shape is {frame.shape}")
        raw = self._native.process(frame, timestamp_s)
        return _result(raw)

    @property
    def faces(self) -> Optional[np.ndarray]:
        """The mesh's triangles ``(F, 3)`` int32, once a frame had a mesh."""
        return self._native.triangles

    @property
    def intrinsics(self) -> Optional[Tuple[float, float, float, float]]:
        """``(fx, fy, cx, cy)`` in pixels, once the first frame set the size."""
        return self._native.intrinsics


def _result(raw: Dict[str, Any]) -> FrameResult:
    metrics = json.loads(raw["metrics_json"])
    weights = raw["weights"]
    blendshapes = {} if weights is None else {n: float(w) for n, w in zip(ARKIT_BLENDSHAPES, weights)}
    head = raw["head"]
    return FrameResult(
        index=raw["index"],
        status=metrics.get("status", ""),
        vertices=raw["vertices"],
        landmarks=raw["landmarks"],
        blendshapes=blendshapes,
        blendshape_array=weights,
        head_pose=raw["head_pose"],
        head_angles=None if head is None else tuple(float(a) for a in head),
        metrics=metrics,
    )


@dataclass(frozen=True)
class Frame:
    """A frame read by :func:`open`."""

    index: int
    #: Seconds from the input's start, when the input says.
    timestamp_s: Optional[float]
    #: ``(H, W, 3)`` uint8 RGB.
    image: np.ndarray


class _Frames:
    def __init__(self, path: PathLike) -> None:
        self._native = NativeFrames(os.fspath(path))
        self.size: Tuple[int, int] = self._native.size
        self.fps: Optional[float] = self._native.fps

    def __iter__(self) -> Iterator[Frame]:
        for index, timestamp_s, image in self._native:
            yield Frame(index, timestamp_s, image)


def open(path: PathLike) -> _Frames:  # noqa: A001 - as io.open, for frames
    """The frames of a video (through FFmpeg), an image folder or an image, as ``visage run``
    reads them: iterate for :class:`Frame` s; ``.size`` is ``(width, height)``, ``.fps`` the
    frame rate when known."""
    return _Frames(path)


@dataclass(frozen=True)
class RunData:
    """A run folder (``visage run``'s output) loaded into numpy."""

    #: The fused mesh per frame, ``(frames, V, 3)`` float32, metres, camera coordinates as
    #: :attr:`FrameResult.vertices` (``sequence.pc2``, which holds them in OBJ's y-up axes:
    #: ``(x, −y, −z)``).
    vertices: Optional[np.ndarray]
    #: ``(F, 3)`` int32 (``mesh.obj``).
    faces: Optional[np.ndarray]
    #: ``(frames, 52)`` float32 (``blendshapes.csv``), and the names of its columns.
    blendshapes: Optional[np.ndarray]
    blendshape_names: List[str]
    #: ``landmarks.json`` and ``metrics.json`` as parsed JSON.
    landmarks: Optional[Dict[str, Any]]
    metrics: Dict[str, Any]


def read_run(out_dir: PathLike) -> RunData:
    """Loads a run folder written by ``visage run`` (or ``visage live --out``)."""
    out = Path(out_dir)
    metrics_path = out / "metrics.json"
    if not metrics_path.is_file():
        raise VisageError(f"{out}: not a visage run folder (no metrics.json)")
    metrics = json.loads(metrics_path.read_text())
    vertices = _read_pc2(out / "sequence.pc2") if (out / "sequence.pc2").is_file() else None
    faces = _read_obj_faces(out / "mesh.obj") if (out / "mesh.obj").is_file() else None
    blendshapes, names = None, []
    if (out / "blendshapes.csv").is_file():
        with (out / "blendshapes.csv").open(newline="") as f:
            rows = list(csv.reader(f))
        header = rows[0]
        start = header.index("BlendShapeCount") + 1
        names = header[start : start + 52]
        blendshapes = np.array([[float(v) for v in r[start : start + 52]] for r in rows[1:]], dtype=np.float32)
    landmarks = json.loads((out / "landmarks.json").read_text()) if (out / "landmarks.json").is_file() else None
    return RunData(vertices, faces, blendshapes, names, landmarks, metrics)


def _read_pc2(path: Path) -> np.ndarray:
    data = path.read_bytes()
    if data[:12] != b"POINTCACHE2\0":
        raise VisageError(f"{path}: not a point cache (PC2)")
    _version, points, _start, _rate, samples = struct.unpack_from("<iiffi", data, 12)
    array = np.frombuffer(data, dtype="<f4", count=samples * points * 3, offset=32)
    # OBJ's y-up axes back to camera coordinates (x right, y down, z forward).
    return array.reshape(samples, points, 3) * np.array([1.0, -1.0, -1.0], dtype=np.float32)


def _read_obj_faces(path: Path) -> np.ndarray:
    faces = []
    with path.open() as f:
        for line in f:
            if line.startswith("f "):
                faces.append([int(tok.split("/")[0]) - 1 for tok in line.split()[1:4]])
    return np.asarray(faces, dtype=np.int32)
