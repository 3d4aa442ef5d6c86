use std::path::PathBuf;
use visage::{Input, Reconstructor};
use visage_morphable::{FaceFitter, FaceModel, FitOptions};
fn main() {
    let args: Vec<String> = std::env::args().collect();
    let input = Input::open(&PathBuf::from(&args[1])).unwrap();
    let fov: f64 = std::env::var("FOV")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(60.0);
    let k = *Reconstructor::builder()
        .fov_deg(fov)
        .build_for(&input)
        .unwrap()
        .intrinsics();
    let mut rec = Reconstructor::builder()
        .model(visage::ModelSource::None)
        .build_for(&input)
        .unwrap();
    let model = FaceModel::embedded();
    let ep: f64 = std::env::var("EP")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(0.3);
    let env = |k: &str, d: f64| {
        std::env::var(k)
            .ok()
            .and_then(|v| v.parse().ok())
            .unwrap_or(d)
    };
    let mut fitter = FaceFitter::new(
        &model,
        FitOptions {
            expression_prior: ep,
            outline_weight: env("OW", 0.2),
            expression_sparsity: env("L1", 0.0),
            rigid_motion_m: env("RIGID", 0.004),
            ..FitOptions::default()
        },
    );
    let jaw = model.expression_index("jawOpen").unwrap();
    let (bl, br) = (
        model.expression_index("eyeBlink_L").unwrap(),
        model.expression_index("eyeBlink_R").unwrap(),
    );
    let (mut jaws, mut gaps, mut blinks, mut ears) =
        (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    let mut static_w = vec![0.0f64; model.expression_names.len()];
    let mut sum = vec![[0.0f64; 2]; 468];
    let mut sq = vec![0.0f64; 468];
    let mut n = 0;
    let (mut outline_err, mut inner_err) = (0.0f64, 0.0f64);
    let mut proj = Vec::new();
    for frame in input {
        let frame = frame.unwrap();
        let r = rec.process(&frame).unwrap();
        let Some(face) = r.landmarks.faces.first() else {
            continue;
        };
        let l: Vec<[f64; 2]> = face.landmarks.iter().map(|p| [p[0], p[1]]).collect();
        let fit = fitter.fit(&k, &l, None);
        let d = |a: usize, b: usize| (l[a][0] - l[b][0]).hypot(l[a][1] - l[b][1]);
        jaws.push(fit.expression[jaw]);
        gaps.push(d(13, 14) / d(33, 263));
        blinks.push(fit.expression[bl].max(fit.expression[br]));
        ears.push(-(d(159, 145) / d(33, 133) + d(386, 374) / d(362, 263)));
        for (s, w) in static_w.iter_mut().zip(&fit.expression) {
            *s += w;
        }
        fitter.projected_landmarks(&k, &mut proj);
        for j in 0..468 {
            let d = [proj[j][0] - l[j][0], proj[j][1] - l[j][1]];
            sum[j][0] += d[0];
            sum[j][1] += d[1];
            sq[j] += d[0] * d[0] + d[1] * d[1];
            if visage_morphable::fit::FACE_OVAL.contains(&j) {
                outline_err += d[0].hypot(d[1]) / 36.0;
            } else {
                inner_err += d[0].hypot(d[1]) / 432.0;
            }
        }
        n += 1;
        if n == 100 {
            let mut img = frame.image.clone();
            for j in 0..468 {
                for (p, col) in [(l[j], [0u8, 255, 0]), (proj[j], [255u8, 0, 0])] {
                    let (x, y) = (p[0].round() as i64, p[1].round() as i64);
                    if x >= 0 && y >= 0 && (x as u32) < img.width() && (y as u32) < img.height() {
                        img.put_pixel(x as u32, y as u32, image::Rgb(col));
                    }
                }
            }
            let (cx, cy) = (l[168][0] as i64, l[168][1] as i64);
            let crop = image::imageops::crop_imm(
                &img,
                (cx - 110).max(0) as u32,
                (cy - 70).max(0) as u32,
                220,
                140,
            )
            .to_image();
            let big =
                image::imageops::resize(&crop, 880, 560, image::imageops::FilterType::Nearest);
            big.save("/tmp/eyes.png").unwrap();
        }
        if n % 50 == 0 {
            eprintln!("frame {n}: {:.2} px", fit.mean_error_px);
        }
    }
    let nf = n as f64;
    let mut rows: Vec<(usize, f64, f64)> = (0..468)
        .map(|j| {
            let m = [sum[j][0] / nf, sum[j][1] / nf];
            let bias = m[0].hypot(m[1]);
            let rms = (sq[j] / nf).sqrt();
            (j, bias, rms)
        })
        .collect();
    let tot_bias: f64 = rows.iter().map(|r| r.1 * r.1).sum::<f64>() / 468.0;
    let tot: f64 = rows.iter().map(|r| r.2 * r.2).sum::<f64>() / 468.0;
    let r = |a: &[f64], b: &[f64]| {
        let n = a.len() as f64;
        let (ma, mb) = (a.iter().sum::<f64>() / n, b.iter().sum::<f64>() / n);
        let cov: f64 = a.iter().zip(b).map(|(x, y)| (x - ma) * (y - mb)).sum();
        let va: f64 = a.iter().map(|x| (x - ma).powi(2)).sum();
        let vb: f64 = b.iter().map(|y| (y - mb).powi(2)).sum();
        cov / (va * vb).sqrt()
    };
    let mut top: Vec<(f64, &String)> = static_w
        .iter()
        .map(|w| w / nf)
        .zip(&model.expression_names)
        .collect();
    top.sort_by(|a, b| b.0.partial_cmp(&a.0).unwrap());
    println!(
        "r(jaw, gap) {:.3}  r(blink, -EAR) {:.3}  mean weights {:?}",
        r(&jaws, &gaps),
        r(&blinks, &ears),
        top[..5]
            .iter()
            .map(|(v, n)| format!("{n} {v:.2}"))
            .collect::<Vec<_>>()
    );
    println!(
        "mean px: outline {:.2}, others {:.2}",
        outline_err / nf,
        inner_err / nf
    );
    println!(
        "rms total {:.2} px, of which systematic (bias) {:.2} px",
        tot.sqrt(),
        tot_bias.sqrt()
    );
    rows.sort_by(|a, b| b.1.partial_cmp(&a.1).unwrap());
    for r in rows
        .iter()
        .filter(|r| !visage_morphable::fit::FACE_OVAL.contains(&r.0))
        .take(25)
    {
        println!("landmark {:3}: bias {:.2} px, rms {:.2}", r.0, r.1, r.2);
    }
}
