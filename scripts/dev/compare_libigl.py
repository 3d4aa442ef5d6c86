#!/usr/bin/env python3
"""Dev-only: visage's 3-D operators against libigl's (pip install libigl numpy scipy).

    python3 scripts/dev/compare_libigl.py MESH.obj|ply [MESH…]

For each mesh: the cotangent Laplacian (visage's is libigl's cotmatrix negated), the mixed
Voronoi areas (massmatrix, MASSMATRIX_TYPE_VORONOI), the mean curvature at interior vertices
(|M⁻¹ L V| / 2) and the Gaussian curvature's angle defects (igl.gaussian_curvature), each as
the largest relative difference. Runs `cargo run --release -p visage-fem --example
surface_operators` to get visage's.
"""
import json
import os
import subprocess
import sys
import tempfile

import igl
import numpy as np
import scipy.sparse as sp

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..")


def visage_operators(mesh):
    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, "ops.json")
        subprocess.run(
            ["cargo", "run", "-q", "--release", "-p", "visage-fem", "--example",
             "surface_operators", "--", os.path.abspath(mesh), out],
            cwd=ROOT, check=True)
        with open(out) as f:
            return json.load(f)


def rel(a, b):
    """Largest |a − b| over the largest |b|."""
    a, b = np.asarray(a, float), np.asarray(b, float)
    return float(np.max(np.abs(a - b)) / max(np.max(np.abs(b)), 1e-300))


def compare(mesh):
    ops = visage_operators(mesh)
    v = np.array(ops["vertices"], float)
    f = np.array(ops["triangles"], np.int64)
    n = len(v)
    i, j, x = zip(*ops["laplacian"])
    l_visage = sp.csr_matrix((x, (i, j)), shape=(n, n)).toarray()
    l_igl = -igl.cotmatrix(v, f).toarray()
    m_igl = igl.massmatrix(v, f, igl.MASSMATRIX_TYPE_VORONOI).diagonal()
    hn = (l_igl @ v) / (2.0 * m_igl[:, None])
    h_igl = np.linalg.norm(hn, axis=1)
    interior = ~np.array(ops["boundary"])
    h_visage = np.array([h if h is not None else np.nan for h in ops["mean_curvature"]])
    k_igl = igl.gaussian_curvature(v, f)
    defect = np.array(ops["angle_defect"])
    print(f"{mesh}: {n} vertices, {len(f)} triangles, {int((~interior).sum())} on the boundary")
    print(f"  cotangent Laplacian   max rel diff {rel(l_visage, l_igl):.2e}")
    print(f"  mixed Voronoi areas   max rel diff {rel(ops['mixed_area'], m_igl):.2e}")
    print(f"  mean curvature (int.) max rel diff {rel(h_visage[interior], h_igl[interior]):.2e}")
    print(f"  angle defect (int.)   max rel diff {rel(defect[interior], k_igl[interior]):.2e}")


if __name__ == "__main__":
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    for m in sys.argv[1:]:
        compare(m)
