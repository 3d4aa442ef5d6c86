//! Writes a mesh's 3-D operators as JSON, for `scripts/dev/compare_libigl.py`: the cotangent
//! Laplacian's entries, the mixed Voronoi areas, the mean curvature and the angle defects.
//!
//! `cargo run --release -p visage-fem --example surface_operators -- MESH.obj|ply OUT.json`

use std::io::Write;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [mesh, out] = args.as_slice() else {
        return Err("usage: surface_operators MESH.obj|ply OUT.json".into());
    };
    let mesh = visage_mesh::io::read_mesh(mesh.as_ref())?;
    let l = visage_fem::cotan_laplacian(&mesh.vertices, &mesh.triangles)?;
    let mut entries = Vec::new();
    visage_fem::sparse::for_each_entry(&l, |i, j, v| entries.push((i, j, v)));
    let g = visage_fem::surface_geometry(&mesh.vertices, &mesh.triangles);
    let nan_to_null =
        |v: &[f64]| -> Vec<Option<f64>> { v.iter().map(|x| x.is_finite().then_some(*x)).collect() };
    let json = serde_json::json!({
        "vertices": mesh.vertices,
        "triangles": mesh.triangles,
        "laplacian": entries,
        "mixed_area": g.area,
        "mean_curvature": nan_to_null(&g.mean_curvature),
        "angle_defect": g.angle_defect,
        "boundary": g.boundary,
    });
    std::fs::File::create(out)?.write_all(json.to_string().as_bytes())?;
    Ok(())
}
