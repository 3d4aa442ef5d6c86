"""visage: metric 3-D face meshes, ARKit blendshapes and head pose from ordinary RGB video, on a CPU.

The Rust library visage as a Python package::

    import visage

    rec = visage.Reconstructor()
    for frame in visage.open("face.mp4"):
        result = rec.process(frame.image, timestamp_s=frame.timestamp_s)
        print(result.status, result.blendshapes.get("jawOpen"), result.head_angles)

- :class:`Reconstructor` processes ``(H, W, 3)`` uint8 RGB frames one at a time (causally: each
  frame's result as soon as it is given; with ``latency`` frames of look-ahead through
  :meth:`Reconstructor.push`), with the GIL released while it works.
- :func:`run` is ``visage run`` as a call: a clip into an output folder, the same files (its
  exports included: ``glb=True``, ``report=True``, …).
- :func:`open` reads a video, an image folder or an image as visage does.
- :func:`read_run` loads a run folder written by ``visage run`` (or :func:`run`) into numpy.

Coordinates: camera coordinates, x right, y down, z forward, metres; pixel ``(i, j)``'s centre
at ``(i, j)``. Errors from visage are :class:`VisageError`, with the command line's message.
"""

from __future__ import annotations

import csv
import json
import logging
import os
import struct
import warnings
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Dict, Iterator, List, Optional, Sequence, Tuple, Union

import numpy as np

from ._visage import ARKIT_BLENDSHAPES, NativeFrames, NativeReconstructor, VisageError
from ._visage import run as _native_run

__all__ = [
    "ARKIT_BLENDSHAPES",
    "Frame",
    "FrameResult",
    "Reconstructor",
    "RunData",
    "RunResult",
    "VisageError",
    "open",
    "read_run",
    "run",
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
    #: ``(478, 2)`` float32, frame pixels, in MediaPipe's order (its ``refine_landmarks`` /
    #: FaceLandmarker output): the 468 tracked landmarks, then the subject's right iris
    #: (468: centre, 469–472: rim) and the left one (473: centre, 474–477: rim) from the iris
    #: network. The ten iris rows are NaN when the irises are unknown for the frame (see
    #: :attr:`has_irises`); ``None`` without a face.
    landmarks: Optional[np.ndarray]
    #: Whether the iris rows of :attr:`landmarks` hold points: the iris network runs with the
    #: face-model fit when its file (``iris_landmark.tflite``) is in the model folder.
    has_irises: bool
    #: The 52 ARKit blendshape weights by name (empty without a face).
    blendshapes: Dict[str, float]
    #: The same in ARKit's order (:data:`ARKIT_BLENDSHAPES`), ``(52,)`` float32, or ``None``.
    blendshape_array: Optional[np.ndarray]
    #: Model → camera, ``(4, 4)`` float64 (the metric head pose), or ``None``.
    head_pose: Optional[np.ndarray]
    #: Live Link Face's head ``(yaw, pitch, roll)`` in radians (yaw > 0 turning to the
    #: subject's right, pitch > 0 looking down), or ``None``.
    head_angles: Optional[Tuple[float, float, float]]
    #: The face's identity as the fit has settled on it by this frame: weights of the face
    #: model's identity modes (about N(0, 1) each a priori), ``(K,)`` float64; it firms up
    #: over the first frames and stays the same person's. ``None`` before a face was fitted.
    identity: Optional[np.ndarray]
    #: The frame's record as ``metrics.json`` has it (stage times in ``metrics["ms"]``).
    metrics: Dict[str, Any] = field(repr=False)

    @property
    def timings_ms(self) -> Dict[str, float]:
        """Milliseconds per stage of this frame, as ``metrics.json`` has them: ``decode``,
        ``track`` (detection, landmarks, the smoother), ``fit`` (the metric fit, the face
        model, the eyes), ``depth``, ``fuse``, ``write`` (the result's surfaces),
        ``keypoints``."""
        return dict(self.metrics.get("ms", {}))


#: A camera's intrinsics: an intrinsics JSON file (``visage run --intrinsics``'s), ``(fx, fy,
#: cx, cy)`` in pixels, or OpenCV's ``(3, 3)`` camera matrix.
IntrinsicsLike = Union[PathLike, Sequence[float], np.ndarray]


def _check_frame(frame: Any) -> None:
    if not isinstance(frame, np.ndarray):
        raise ValueError(f"a frame is an (H, W, 3) uint8 RGB numpy array, not {type(frame).__name__}")
    if frame.dtype != np.uint8:
        raise ValueError(f"a frame is an (H, W, 3) uint8 RGB array; this one's dtype is {frame.dtype}")
    if frame.ndim != 3 or frame.shape[2] != 3:
        raise ValueError(f"a frame is an (H, W, 3) uint8 RGB array; this one's shape is {frame.shape}")


def _bgr_looking(frame: np.ndarray, landmarks: np.ndarray) -> bool:
    """Whether the face in ``frame`` (inside the box of its 468 landmarks) is bluer than it is
    red: skin of every tone is redder than blue in daylight and indoor light, so a face that is
    not is most likely a BGR frame (OpenCV's order) given as RGB. Not an error: a scene lit in
    blue can do it too."""
    points = landmarks[:468]
    if not np.isfinite(points).all():
        return False
    h, w = frame.shape[:2]
    x0, y0 = np.clip(np.floor(points.min(0)).astype(int), 0, [w - 1, h - 1])
    x1, y1 = np.clip(np.ceil(points.max(0)).astype(int), 0, [w - 1, h - 1])
    if x1 <= x0 or y1 <= y0:
        return False
    face = frame[y0 : y1 + 1 : 4, x0 : x1 + 1 : 4].reshape(-1, 3).astype(np.float64)
    red, blue = face[:, 0].mean(), face[:, 2].mean()
    return blue > 1.05 * red


class Reconstructor:
    """Metric face meshes, blendshapes and head pose from frames, one at a time.

    Args:
        fov_deg: the camera's horizontal field of view in degrees (default: visage's guess,
            60°, as ``visage run`` makes it for a video).
        intrinsics: the camera instead: an intrinsics JSON file (``visage run --intrinsics``'s,
            for the frames' size), ``(fx, fy, cx, cy)`` in pixels, or OpenCV's ``(3, 3)``
            camera matrix. Not with ``fov_deg``.
        mode: ``"streaming"`` (causal, frame by frame). ``"clip"`` — the exact minimiser over
            a whole clip — needs every frame at once: :func:`run` with ``mode="clip"``.
        latency: frames the landmark smoother waits for before it gives a frame out. 0 (the
            default): :meth:`process` gives each frame's result at once. 1 or more: give frames
            with :meth:`push`, which returns the frames it completed (with 1, the frame before;
            each frame's landmarks then see where the motion went next, as ``visage run``'s
            default ``--latency 1``), and call :meth:`end` after the last.
        models: folder of the model files (default: ``$VISAGE_MODELS``, else the wheel's own).

    One reconstructor follows one video: its frames must keep one size. It keeps its state
    (the face's identity, the temporal smoothing) from frame to frame. Use one per video; a
    reconstructor may be used from any thread, one call at a time, and two reconstructors on
    two threads run at once.
    """

    def __init__(
        self,
        fov_deg: Optional[float] = None,
        intrinsics: Optional[IntrinsicsLike] = None,
        mode: str = "streaming",
        latency: int = 0,
        models: Optional[PathLike] = None,
    ) -> None:
        focal, file = None, None
        if isinstance(intrinsics, (str, os.PathLike)):
            file = os.fspath(intrinsics)
        elif intrinsics is not None:
            k = np.asarray(intrinsics, dtype=np.float64)
            if k.shape == (3, 3):
                focal = (k[0, 0], k[1, 1], k[0, 2], k[1, 2])
            elif k.shape == (4,):
                focal = tuple(float(x) for x in k)
            else:
                raise ValueError(
                    f"intrinsics: a file, (fx, fy, cx, cy) or a (3, 3) camera matrix; this one's shape is {k.shape}"
                )
        self._native = NativeReconstructor(fov_deg, focal, file, mode, latency, _models_dir(models))
        self._colours_checked = False

    def _check_colours(self, frame: np.ndarray, results: List[FrameResult]) -> None:
        """Once, at the first frame with a face: a warning when it looks like BGR."""
        if self._colours_checked:
            return
        for r in results:
            if r.landmarks is None:
                continue
            self._colours_checked = True
            if _bgr_looking(frame, r.landmarks):
                warnings.warn(
                    "the face in this frame is bluer than red: is it BGR (OpenCV's order)? "
                    "visage takes RGB: cv2.cvtColor(frame, cv2.COLOR_BGR2RGB)",
                    stacklevel=3,
                )
            return

    def process(self, frame: np.ndarray, timestamp_s: Optional[float] = None) -> FrameResult:
        """Processes one frame and returns its result (``latency=0``, the default; else use
        :meth:`push`): an ``(H, W, 3)`` uint8 RGB array (OpenCV's frames are BGR:
        ``cv2.cvtColor(frame, cv2.COLOR_BGR2RGB)``; a warning says so when the first face
        found is bluer than red). ``timestamp_s``: its time in seconds,
        when known (else the frames are taken 1/30 s apart)."""
        _check_frame(frame)
        result = _result(self._native.process(frame, timestamp_s))
        self._check_colours(frame, [result])
        return result

    def push(self, frame: np.ndarray, timestamp_s: Optional[float] = None) -> List[FrameResult]:
        """Gives one frame (as :meth:`process`) and returns the frames it completed, in input
        order: with ``latency=1`` the frame before it (none after the first frame); at a cut
        or a lost face also the frames held back. With ``latency=0``, this frame."""
        _check_frame(frame)
        results = [_result(raw) for raw in self._native.push(frame, timestamp_s)]
        # The results may be of earlier frames (the latency): their face is still near.
        self._check_colours(frame, results)
        return results

    def end(self) -> List[FrameResult]:
        """The input has ended: the frames the smoother still held back, in input order."""
        return [_result(raw) for raw in self._native.end()]

    @property
    def faces(self) -> Optional[np.ndarray]:
        """The mesh's triangles ``(F, 3)`` int32, once a frame had a mesh."""
        return self._native.triangles

    @property
    def uvs(self) -> Optional[np.ndarray]:
        """The mesh's texture coordinates ``(V, 2)`` float32 (``mesh.obj``'s), once a frame
        had a mesh."""
        return self._native.uvs

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
        has_irises=raw["has_irises"],
        blendshapes=blendshapes,
        blendshape_array=weights,
        head_pose=raw["head_pose"],
        head_angles=None if head is None else tuple(float(a) for a in head),
        identity=raw["identity"],
        metrics=metrics,
    )


@dataclass(frozen=True)
class RunResult:
    """What :func:`run` did (the files are in ``out_dir``: :func:`read_run` loads them)."""

    out_dir: Path
    #: Frames this call processed (a resumed run's warm-up included).
    frames: int
    #: Frames of the folder's run with a mesh (a resumed run's earlier ones included).
    meshed: int
    #: Frames the folder's files hold.
    kept: int
    #: The run's summary as ``metrics.json`` has it (frames per second, peak memory, the
    #: quality figures, per-stage times); ``None`` when ``resume=True`` found the run complete.
    summary: Optional[Dict[str, Any]] = field(repr=False)
    #: What the exports wrote, as ``export.json`` has it (``files`` with their sizes and
    #: times, the glb's morph targets and error, the texture's frames); ``None`` without
    #: exports.
    exports: Optional[Dict[str, Any]] = field(default=None, repr=False)
    #: With ``faces="all"``: each face's run, into its folder ``out_dir / "face-N"``, left to
    #: right (the fields above are then their sums, ``summary`` and ``exports`` ``None``);
    #: else empty.
    faces: Tuple["RunResult", ...] = ()


_log = logging.getLogger("visage")


def _notify(kind: str, message: str) -> None:
    """Where :func:`run`'s warnings (a face lost, other faces in view) and notices (what a
    resumed run kept) go: :mod:`warnings` and the ``visage`` logger."""
    if kind == "warning":
        warnings.warn(message, RuntimeWarning, stacklevel=3)
    else:
        _log.info(message)


def run(
    input: Optional[PathLike],  # noqa: A002 - the command line's INPUT
    out_dir: PathLike,
    *,
    progress: Optional[Callable[[int, Optional[int]], Any]] = None,
    rgbd: Optional[PathLike] = None,
    depth_scale: Optional[float] = None,
    depth_intrinsics: Optional[PathLike] = None,
    depth_to_color: Optional[PathLike] = None,
    keep_depth_edges: bool = False,
    depth_config: Optional[PathLike] = None,
    intrinsics: Optional[PathLike] = None,
    fov_deg: Optional[float] = None,
    depth: Optional[str] = None,
    lambda_: Optional[float] = None,
    mu: Optional[float] = None,
    smoothing: Optional[Union[float, str]] = None,
    latency: Optional[int] = None,
    mesh: Optional[str] = None,
    mode: Optional[str] = None,
    subdivision: Optional[int] = None,
    fair: Optional[float] = None,
    keypoints: bool = False,
    spacing: Optional[int] = None,
    every: Optional[int] = None,
    max_frames: Optional[int] = None,
    models: Optional[PathLike] = None,
    model: Optional[PathLike] = None,
    no_fit: bool = False,
    ply: bool = False,
    save_raw: bool = False,
    ascii: bool = False,  # noqa: A002 - the command line's --ascii
    overwrite: bool = False,
    resume: bool = False,
    faces: Optional[str] = None,
    glb: bool = False,
    texture: bool = False,
    plots: bool = False,
    report: bool = False,
    preview: bool = False,
) -> RunResult:
    """``visage run INPUT --out OUT_DIR [options]`` as a call: the same files in ``out_dir``
    (``sequence.pc2`` with ``mesh.obj``, ``landmarks.json``, ``blendshapes.csv``,
    ``camera.json``, ``metrics.json``; PLYs with ``ply``/``save_raw``; ``sequence.glb``,
    ``texture.png``, ``plots/``, ``report.html``, ``preview.mp4`` and ``export.json`` with
    ``glb``, ``texture``, ``plots``, ``report``, ``preview``), the same errors
    (:class:`VisageError`, with the command line's message). The options fill the same
    settings as the flags, and the run is the command line's own code.

    The options are the flags' (``visage run --help`` says what each does), snake_case:
    ``fov_deg`` is ``--fov-deg``, ``lambda_`` is ``--lambda``, ``smoothing`` a number or
    ``"off"``, ``faces`` ``"largest"`` or ``"all"``; ``None`` is the flag's default. An
    RGB-D recording is ``run(None, out_dir, rgbd=folder)``. Not here: ``--quiet`` (nothing is
    printed). With ``faces="all"`` each face of the first frame that shows one goes into its
    own ``out_dir / "face-N"``, with ``faces.json`` listing them (:attr:`RunResult.faces`).

    ``progress(frames_done, frames_total)`` is called after every frame (``frames_total`` is
    ``None`` when the input does not say; with ``faces="all"`` it starts again for each face),
    with the GIL held only for the call; if it raises, the run stops as after Ctrl-C — the
    frames so far are written and ``metrics.json`` says ``"interrupted"`` — and its exception
    is raised. Ctrl-C does the same (:class:`KeyboardInterrupt`). Warnings go to
    :mod:`warnings`, notices (the camera assumed, what ``overwrite`` removed, what a resume
    kept) to the ``visage`` logger. Options that conflict, or one without another it needs,
    raise :class:`ValueError`, as the command line refuses them; an unknown option raises
    :class:`TypeError`.
    """

    def path(p: Optional[PathLike]) -> Optional[str]:
        return None if p is None else os.fspath(p)

    raw = _native_run(
        path(input),
        os.fspath(out_dir),
        _notify,
        progress,
        rgbd=path(rgbd),
        depth_scale=depth_scale,
        depth_intrinsics=path(depth_intrinsics),
        depth_to_color=path(depth_to_color),
        keep_depth_edges=keep_depth_edges,
        depth_config=path(depth_config),
        intrinsics=path(intrinsics),
        fov_deg=fov_deg,
        depth=depth,
        lambda_=lambda_,
        mu=mu,
        smoothing=None if smoothing is None else str(smoothing),
        latency=latency,
        mesh=mesh,
        mode=mode,
        subdivision=subdivision,
        fair=fair,
        keypoints=keypoints,
        spacing=spacing,
        every=every,
        max_frames=max_frames,
        models=_models_dir(models),
        model=path(model),
        no_fit=no_fit,
        ply=ply,
        save_raw=save_raw,
        ascii=ascii,
        overwrite=overwrite,
        resume=resume,
        faces=faces,
        glb=glb,
        texture=texture,
        plots=plots,
        report=report,
        preview=preview,
    )
    runs = [
        RunResult(
            out_dir=Path(face["dir"]),
            frames=face["frames"],
            meshed=face["meshed"],
            kept=face["kept"],
            summary=None if face["summary_json"] is None else json.loads(face["summary_json"]),
            exports=None if face["exports_json"] is None else json.loads(face["exports_json"]),
        )
        for face in raw
    ]
    if faces != "all":
        return runs[0]
    return RunResult(
        out_dir=Path(out_dir),
        frames=sum(r.frames for r in runs),
        meshed=sum(r.meshed for r in runs),
        kept=sum(r.kept for r in runs),
        summary=None,
        faces=tuple(runs),
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
