//! Per frame, each eye's aperture as the 468-point mesh and the iris network's eye contour see
//! it (upper to lower lid centre over the corners' distance), as CSV on stdout.
//!
//! ```sh
//! cargo run --release -p visage-face --example eye_apertures -- MODELS VIDEO > apertures.csv
//! ```

use std::path::PathBuf;

use visage_face::{Eye, FaceMesh, FaceTracker, IrisLandmarker};
use visage_video::FrameSource;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args_os().skip(1).map(PathBuf::from);
    let (Some(models), Some(video)) = (args.next(), args.next()) else {
        return Err("usage: eye_apertures MODELS VIDEO".into());
    };
    let mut tracker = FaceTracker::new(FaceMesh::load(&models)?);
    let mut iris = IrisLandmarker::load(&models)?;
    println!("frame,mesh_r,mesh_l,contour_r,contour_l,c4_vs_145,c12_vs_159");
    for (i, frame) in FrameSource::open(&video)?.enumerate() {
        let frame = frame?;
        let Some(face) = tracker.track(&frame.image)?.face else {
            println!("{i},,,,,,");
            continue;
        };
        let p = &face.landmarks.points;
        let d = |a: [f32; 3], b: [f32; 3]| ((a[0] - b[0]).hypot(a[1] - b[1])) as f64;
        let mesh = |[u, l, a, b]: [usize; 4]| d(p[u], p[l]) / d(p[a], p[b]);
        let mut row = vec![mesh([159, 145, 33, 133]), mesh([386, 374, 362, 263])];
        let mut check = [0.0; 2];
        for eye in Eye::BOTH {
            let e = iris.eye(&frame.image, p, eye)?;
            let c = &e.contour;
            row.push(d(c[12], c[4]) / d(c[0], c[8]));
            if eye == Eye::Right {
                check = [d(c[4], p[145]), d(c[12], p[159])];
            }
        }
        println!(
            "{i},{:.4},{:.4},{:.4},{:.4},{:.2},{:.2}",
            row[0], row[1], row[2], row[3], check[0], check[1]
        );
    }
    Ok(())
}
