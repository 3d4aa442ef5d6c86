"""Types of the native module (crates/python); use the package's API instead."""

from typing import Any, Callable, Dict, Iterator, List, Optional, Tuple

import numpy as np

ARKIT_BLENDSHAPES: List[str]

class VisageError(RuntimeError): ...

class NativeReconstructor:
    def __init__(
        self,
        fov_deg: Optional[float] = ...,
        intrinsics: Optional[Tuple[float, float, float, float]] = ...,
        intrinsics_file: Optional[str] = ...,
        mode: str = ...,
        latency: int = ...,
        models: Optional[str] = ...,
    ) -> None: ...
    def process(self, frame: np.ndarray, timestamp_s: Optional[float] = ...) -> Dict[str, Any]: ...
    def push(self, frame: np.ndarray, timestamp_s: Optional[float] = ...) -> List[Dict[str, Any]]: ...
    def end(self) -> List[Dict[str, Any]]: ...
    @property
    def triangles(self) -> Optional[np.ndarray]: ...
    @property
    def uvs(self) -> Optional[np.ndarray]: ...
    @property
    def intrinsics(self) -> Optional[Tuple[float, float, float, float]]: ...

class NativeFrames:
    def __init__(self, path: str) -> None: ...
    @property
    def size(self) -> Tuple[int, int]: ...
    @property
    def fps(self) -> Optional[float]: ...
    def __iter__(self) -> Iterator[Tuple[int, Optional[float], np.ndarray]]: ...
    def __next__(self) -> Tuple[int, Optional[float], np.ndarray]: ...

def run(
    input: Optional[str],
    out_dir: str,
    notify: Callable[[str, str], Any],
    progress: Optional[Callable[[int, Optional[int]], Any]] = ...,
    *,
    rgbd: Optional[str] = ...,
    depth_scale: Optional[float] = ...,
    depth_intrinsics: Optional[str] = ...,
    depth_to_color: Optional[str] = ...,
    keep_depth_edges: bool = ...,
    depth_config: Optional[str] = ...,
    intrinsics: Optional[str] = ...,
    fov_deg: Optional[float] = ...,
    depth: Optional[str] = ...,
    lambda_: Optional[float] = ...,
    mu: Optional[float] = ...,
    smoothing: Optional[str] = ...,
    latency: Optional[int] = ...,
    mesh: Optional[str] = ...,
    mode: Optional[str] = ...,
    subdivision: Optional[int] = ...,
    fair: Optional[float] = ...,
    keypoints: bool = ...,
    spacing: Optional[int] = ...,
    every: Optional[int] = ...,
    max_frames: Optional[int] = ...,
    models: Optional[str] = ...,
    model: Optional[str] = ...,
    no_fit: bool = ...,
    ply: bool = ...,
    save_raw: bool = ...,
    ascii: bool = ...,
    overwrite: bool = ...,
    resume: bool = ...,
    faces: Optional[str] = ...,
    glb: bool = ...,
    texture: bool = ...,
    plots: bool = ...,
    report: bool = ...,
    preview: bool = ...,
) -> List[Dict[str, Any]]: ...
