//! Video in, PLY files out: one fused metric face mesh per frame.
//!
//! ```sh
//! cargo run --release -p visage --example reconstruct -- INPUT OUT
//! ```
//! INPUT: a video, a folder of images or an image. Writes OUT/NNNNNN.ply (metres, camera
//! coordinates) and prints each frame's status. Model files: `visage models fetch`.

use std::path::PathBuf;

use visage::{write_ply, Input, Reconstructor};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args_os().skip(1).map(PathBuf::from);
    let (Some(input), Some(out)) = (args.next(), args.next()) else {
        return Err("usage: reconstruct INPUT OUT".into());
    };
    let input = Input::open(&input)?;
    let mut reconstructor = Reconstructor::builder().build_for(&input)?;
    std::fs::create_dir_all(&out)?;
    for frame in input {
        let result = reconstructor.process(&frame?)?;
        match result.mesh() {
            Some(mesh) => write_ply(&out.join(format!("{:06}.ply", result.index())), mesh)?,
            None => eprintln!("{}", result.warning.unwrap_or("no mesh")),
        }
        println!("frame {}: {:?}", result.index(), result.metrics.status);
    }
    Ok(())
}
