//! A recorded ARKit performance replayed on an ICT-FaceKit head: which rows of a Live Link
//! Face take are played, with which identity and head motion ([`Replay::plan`]), and the
//! frames themselves, rendered as they are read ([`Replay::input`]: a `visage::Input` whose
//! decoding thread is the renderer), so the pipeline takes them exactly as it takes a video.
//!
//! Each played row's 52 ARKit weights drive the model's expressions through
//! [`visage_rig::ArkitToIct`] (ICT's `_L` is ARKit's `Left`, the subject's left; both halves of
//! `browInnerUp` and `cheekPuff` take the whole weight), and its `eyeLook*` weights turn the
//! eyeballs ([`visage_rig::eye_look_gaze`]). In rigid mode the expression is held (neutral, or
//! a chosen row's) while the head moves, so every change in the read weights is a leak of the
//! head's motion.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use visage::run_folder::LiveLinkTake;
use visage::{Frame, Input, VideoError};
use visage_rig::{eye_look_gaze, ArkitToIct, EyeGaze, ARKIT_BLENDSHAPES, ARKIT_BLENDSHAPE_COUNT};

use crate::head_pose_track::{HeadMotion, HeadPose, HeadPoseTrack};
use crate::head_render::{HeadRender, RenderWork};
use crate::normal::standard_normal;
use crate::EvalError;

/// Whose face is rendered.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum IdentityChoice {
    /// One of ICT-FaceKit's identity meshes (`identityNNN.obj`): weight 1 on mode N.
    Mode(usize),
    /// Weights drawn from N(0, 1) with the run's seed.
    Random,
}

/// What is played, and how.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct ReplayOptions {
    pub identity: IdentityChoice,
    /// Seed of the head motion (and of a random identity).
    pub seed: u64,
    pub motion: HeadMotion,
    /// Hold one expression while the head moves: `Some(None)` the neutral face,
    /// `Some(Some(row))` the take's row `row` (counted among the rows with tracking).
    pub rigid: Option<Option<usize>>,
    /// First row played (among the rows with tracking).
    pub start: usize,
    /// Play every `stride`-th row (the frames keep the take's clock: the frame rate drops).
    pub stride: usize,
    /// Play at most this many frames.
    pub max_frames: Option<usize>,
    /// Play only these of the take's weights (indices in `ARKIT_BLENDSHAPES`' order), the
    /// others held at 0 (`None`: all of them).
    pub only: Option<Vec<usize>>,
}

impl Default for ReplayOptions {
    fn default() -> Self {
        ReplayOptions {
            identity: IdentityChoice::Mode(0),
            seed: 0,
            motion: HeadMotion::default(),
            rigid: None,
            start: 0,
            stride: 1,
            max_frames: None,
            only: None,
        }
    }
}

/// One played frame: the truth the pipeline's output is scored against.
#[derive(Clone, Debug, PartialEq)]
pub struct PlayedFrame {
    /// Seconds from the first played frame.
    pub time_s: f64,
    /// The 52 ARKit weights played, [`ARKIT_BLENDSHAPES`]' order.
    pub weights: [f32; ARKIT_BLENDSHAPE_COUNT],
    pub pose: HeadPose,
}

/// A take's plan: the frames to play and whose face plays them.
#[derive(Clone, Debug, PartialEq)]
pub struct Replay {
    /// The take's name (its file stem).
    pub name: String,
    pub frames: Vec<PlayedFrame>,
    /// The identity weights, in the model's mode order.
    pub identity: Vec<f64>,
    /// The played frame rate.
    pub fps: f64,
}

impl Replay {
    /// The frames of `take` (read from `path`) to play with `options`, for a model with
    /// `identity_modes` identity modes. Times come from the take's clock.
    ///
    /// # Errors
    /// Zero stride, a start or held row past the take's end, an identity mode the model lacks,
    /// a bad head motion, a take without a frame rate.
    pub fn plan(
        path: &Path,
        take: &LiveLinkTake,
        options: &ReplayOptions,
        identity_modes: usize,
    ) -> Result<Replay, EvalError> {
        let bad =
            |name: &'static str, value: String, reason: &'static str| EvalError::InvalidConfig {
                name,
                value,
                reason,
            };
        if options.stride == 0 {
            return Err(bad("stride", "0".into(), "must be at least 1"));
        }
        if options.start >= take.rows.len() {
            return Err(bad(
                "start",
                options.start.to_string(),
                "past the take's last row with tracking",
            ));
        }
        let fps = take
            .frame_rate()
            .ok_or_else(|| bad("take", path.display().to_string(), "has no frame rate"))?
            / options.stride as f64;
        let held = match options.rigid {
            Some(Some(row)) => Some(
                take.rows
                    .get(row)
                    .ok_or_else(|| bad("rigid row", row.to_string(), "past the take's end"))?
                    .weights,
            ),
            Some(None) => Some([0.0; ARKIT_BLENDSHAPE_COUNT]),
            None => None,
        };
        let identity = match options.identity {
            IdentityChoice::Mode(n) if n < identity_modes => {
                let mut w = vec![0.0; identity_modes];
                w[n] = 1.0;
                w
            }
            IdentityChoice::Mode(n) => {
                return Err(bad(
                    "identity",
                    n.to_string(),
                    "the model has no such identity mode",
                ))
            }
            IdentityChoice::Random => {
                let mut rng = ChaCha8Rng::seed_from_u64(crate::mix_seed(options.seed ^ 0x1d));
                (0..identity_modes)
                    .map(|_| standard_normal(&mut rng))
                    .collect()
            }
        };
        let track = HeadPoseTrack::new(options.motion, options.seed)?;
        let t0 = take.rows[options.start].time_s;
        let frames = take.rows[options.start..]
            .iter()
            .step_by(options.stride)
            .take(options.max_frames.unwrap_or(usize::MAX))
            .map(|row| {
                let time_s = row.time_s - t0;
                let mut weights = held.unwrap_or(row.weights);
                if let Some(only) = &options.only {
                    for (i, w) in weights.iter_mut().enumerate() {
                        if !only.contains(&i) {
                            *w = 0.0;
                        }
                    }
                }
                PlayedFrame {
                    time_s,
                    weights,
                    pose: track.at(time_s),
                }
            })
            .collect();
        Ok(Replay {
            name: path.file_stem().map_or_else(
                || path.display().to_string(),
                |s| s.to_string_lossy().into_owned(),
            ),
            frames,
            identity,
            fps,
        })
    }

    /// The replay as a pipeline input: frame i is rendered by `render` when the pipeline reads
    /// it, with the frame's index and timestamp; the frames whose index is in `save` are also
    /// written as PNG into `save_dir`.
    pub fn input(
        &self,
        render: Arc<HeadRender>,
        save: Vec<usize>,
        save_dir: Option<PathBuf>,
    ) -> Result<Input, EvalError> {
        let k = *render.intrinsics();
        let to_ict = ArkitToIct::new(&render.model().expression_names);
        let pivot = render.pivot(&self.identity)?;
        let frames = self.frames.clone();
        let identity = self.identity.clone();
        let name = self.name.clone();
        let mut work = RenderWork::default();
        let label = PathBuf::from(format!("{}.csv", self.name));
        let error_path = label.clone();
        let iter = frames.into_iter().enumerate().map(move |(index, played)| {
            let expression = to_ict.weights(&played.weights);
            let image = render
                .render(
                    &identity,
                    &expression,
                    gazes(&played.weights),
                    &played.pose,
                    pivot,
                    &mut work,
                )
                .map_err(|e| VideoError::Image {
                    path: error_path.clone(),
                    reason: format!("frame {index}: {e}"),
                })?;
            if let (true, Some(dir)) = (save.contains(&index), &save_dir) {
                let path = dir.join(format!("{name}_{index:05}.png"));
                image.save(&path).map_err(|e| VideoError::Image {
                    path: path.clone(),
                    reason: e.to_string(),
                })?;
            }
            Ok(Frame {
                index,
                source: format!("{name}:{index}"),
                timestamp_s: Some(played.time_s),
                image,
            })
        });
        Ok(Input::generated(
            &label,
            k.width,
            k.height,
            Some(self.frames.len()),
            Some(self.fps),
            iter,
        ))
    }
}

/// The subject's `[left, right]` gazes that ARKit weights' `eyeLook*` stand for.
pub fn gazes(weights: &[f32; ARKIT_BLENDSHAPE_COUNT]) -> [EyeGaze; 2] {
    let w = |name: &str| {
        ARKIT_BLENDSHAPES
            .iter()
            .position(|n| *n == name)
            .map_or(0.0, |i| f64::from(weights[i]))
    };
    [("Left", true), ("Right", false)].map(|(side, left)| {
        let look = ["Up", "Down", "In", "Out"].map(|dir| w(&format!("eyeLook{dir}{side}")));
        eye_look_gaze(look, left)
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use visage::run_folder::LiveLinkRow;

    fn take(rows: usize) -> LiveLinkTake {
        LiveLinkTake {
            rows: (0..rows)
                .map(|i| {
                    let mut weights = [0.0; ARKIT_BLENDSHAPE_COUNT];
                    weights[17] = i as f32 / rows as f32;
                    LiveLinkRow {
                        row: i,
                        time_s: i as f64 / 30.0,
                        weights,
                    }
                })
                .collect(),
            lost_rows: 0,
            timecode_rate: 60,
        }
    }

    #[test]
    fn plans_follow_start_stride_and_the_takes_clock() {
        let options = ReplayOptions {
            start: 10,
            stride: 3,
            max_frames: Some(5),
            ..ReplayOptions::default()
        };
        let plan = Replay::plan(Path::new("a/take.csv"), &take(100), &options, 30).unwrap();
        assert_eq!(plan.name, "take");
        assert_eq!(plan.frames.len(), 5);
        assert!((plan.fps - 10.0).abs() < 1e-9);
        assert!((plan.frames[2].time_s - 0.2).abs() < 1e-9);
        assert_eq!(plan.frames[2].weights[17], 16.0 / 100.0);
        assert_eq!(plan.identity.iter().sum::<f64>(), 1.0);
        // Rigid: the held expression on every frame, the head still moving.
        let rigid = ReplayOptions {
            rigid: Some(Some(50)),
            ..options.clone()
        };
        let plan = Replay::plan(Path::new("take.csv"), &take(100), &rigid, 30).unwrap();
        assert!(plan.frames.iter().all(|f| f.weights[17] == 0.5));
        assert_ne!(plan.frames[0].pose, plan.frames[4].pose);
        for bad in [
            ReplayOptions {
                stride: 0,
                ..options.clone()
            },
            ReplayOptions {
                start: 100,
                ..options.clone()
            },
            ReplayOptions {
                identity: IdentityChoice::Mode(30),
                ..options.clone()
            },
        ] {
            assert!(Replay::plan(Path::new("t.csv"), &take(100), &bad, 30).is_err());
        }
    }

    #[test]
    fn eye_look_weights_turn_the_eyes_their_way() {
        let mut w = [0.0; ARKIT_BLENDSHAPE_COUNT];
        let at = |n: &str| ARKIT_BLENDSHAPES.iter().position(|x| *x == n).unwrap();
        w[at("eyeLookOutLeft")] = 1.0;
        w[at("eyeLookInRight")] = 1.0;
        w[at("eyeLookUpLeft")] = 0.5;
        let [left, right] = gazes(&w);
        // Both look to the subject's left (positive yaw); only the left eye looks up.
        assert!(left.yaw > 0.4 && right.yaw > 0.4);
        assert!(left.pitch > 0.2 && right.pitch == 0.0);
    }
}
