//! MediaPipe's face detectors ([`DetectorModel`]): BlazeFace short range
//! (`face_detection_short_range.tflite`, the `face_detection_short_range_cpu` graph) and full
//! range (`face_detection_full_range_sparse.tflite`, `face_detection_full_range_cpu`). Both
//! graphs are the same steps with other sizes: letter-box to the square input (128×128 or
//! 192×192), RGB in [−1, 1], decode the SSD anchors (896 or 2304), sigmoid scores, threshold
//! (0.5 or 0.6), weighted NMS (IoU 0.3), remove the letter-box.

use std::path::Path;

use image::RgbImage;

use crate::anchors::{
    blazeface_anchors, full_range_anchors, DETECTOR_INPUT, FULL_RANGE_ANCHORS, FULL_RANGE_INPUT,
    NUM_ANCHORS,
};
use crate::letterbox::{letterbox_bilinear, letterbox_resize, Letterbox};
use crate::nms::{weighted_nms, NMS_IOU_THRESHOLD};
use crate::{sigmoid, Detection, FaceError, ModelFile};
use visage_nn::Network;

/// Minimum face score MediaPipe's short-range face detection keeps (`min_score_thresh`).
pub const DETECTION_SCORE_THRESHOLD: f32 = 0.5;
/// Minimum face score of MediaPipe's full-range face detection (`min_score_thresh` of
/// `face_detection_full_range.pbtxt`).
pub const FULL_RANGE_SCORE_THRESHOLD: f32 = 0.6;

/// Which of MediaPipe's face-detection networks a [`FaceDetector`] runs.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
pub enum DetectorModel {
    /// BlazeFace short range: 128×128 input, 896 anchors; faces wider than about a tenth of
    /// the frame's longer side, ~140 px in a 1280×720 frame (MediaPipe: within ~2 m).
    #[default]
    ShortRange,
    /// Full range: 192×192 input, 2304 anchors (a 48×48 grid); faces down to about 5.5 % of
    /// the frame's longer side, ~70 px in a 1280×720 frame (MediaPipe: within ~5 m), and about
    /// `tile / 16` px with [`FaceDetector::detect_tiled`] (~40 px in 640-px tiles).
    FullRange,
}

impl DetectorModel {
    /// The model file it is loaded from.
    pub fn model_file(self) -> ModelFile {
        match self {
            DetectorModel::ShortRange => ModelFile::FaceDetectionShortRange,
            DetectorModel::FullRange => ModelFile::FaceDetectionFullRange,
        }
    }

    /// Side of the square input, pixels.
    pub fn input_size(self) -> usize {
        match self {
            DetectorModel::ShortRange => DETECTOR_INPUT,
            DetectorModel::FullRange => FULL_RANGE_INPUT,
        }
    }

    /// Number of anchors (rows of the outputs).
    pub fn num_anchors(self) -> usize {
        match self {
            DetectorModel::ShortRange => NUM_ANCHORS,
            DetectorModel::FullRange => FULL_RANGE_ANCHORS,
        }
    }

    /// Anchor centres normalised to the input square, in output order.
    pub fn anchors(self) -> Vec<[f32; 2]> {
        match self {
            DetectorModel::ShortRange => blazeface_anchors(),
            DetectorModel::FullRange => full_range_anchors(),
        }
    }

    /// MediaPipe's `min_score_thresh` for this model.
    pub fn score_threshold(self) -> f32 {
        match self {
            DetectorModel::ShortRange => DETECTION_SCORE_THRESHOLD,
            DetectorModel::FullRange => FULL_RANGE_SCORE_THRESHOLD,
        }
    }

    /// Names of the regressor `[1, N, 16]` and classificator `[1, N, 1]` output tensors.
    fn output_names(self) -> [&'static str; 2] {
        match self {
            DetectorModel::ShortRange => ["regressors", "classificators"],
            DetectorModel::FullRange => ["Identity", "Identity_1"],
        }
    }
}

/// Detector options.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DetectorOptions {
    /// Detections with a lower score are dropped (the model's
    /// [`DetectorModel::score_threshold`]).
    pub score_threshold: f32,
    /// IoU above which weighted NMS merges detections ([`NMS_IOU_THRESHOLD`]).
    pub iou_threshold: f32,
    /// How the frame is resized into the square input.
    pub resize: ResizeFilter,
}

impl DetectorOptions {
    /// MediaPipe's options for `model` (its score threshold, IoU 0.3, bilinear resize).
    pub fn for_model(model: DetectorModel) -> Self {
        DetectorOptions {
            score_threshold: model.score_threshold(),
            iou_threshold: NMS_IOU_THRESHOLD,
            resize: ResizeFilter::default(),
        }
    }
}

/// Resampling of the letter-boxed frame into the detector input.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum ResizeFilter {
    /// Area averaging (anti-aliased; how `shared/reference/facemesh/*/det128.png` was made).
    Area,
    /// Bilinear sampling without anti-aliasing (MediaPipe's CPU `ImageToTensorCalculator`).
    #[default]
    Bilinear,
}

impl Default for DetectorOptions {
    /// The short-range detector's options ([`DetectorOptions::for_model`]).
    fn default() -> Self {
        DetectorOptions::for_model(DetectorModel::ShortRange)
    }
}

/// The compiled detector with its anchors and buffers.
#[derive(Clone, Debug)]
pub struct FaceDetector {
    model: DetectorModel,
    net: Network,
    anchors: Vec<[f32; 2]>,
    /// Options used by [`FaceDetector::detect`].
    pub options: DetectorOptions,
    input_rgb: Vec<u8>,
}

impl FaceDetector {
    /// Loads and verifies `face_detection_short_range.tflite` from the model directory.
    pub fn load(models: &Path) -> Result<Self, FaceError> {
        Self::load_model(DetectorModel::ShortRange, models)
    }

    /// Loads and verifies `face_detection_full_range_sparse.tflite` from the model directory.
    pub fn load_full_range(models: &Path) -> Result<Self, FaceError> {
        Self::load_model(DetectorModel::FullRange, models)
    }

    /// The full-range detector if its file is in the model directory, `None` if it is absent
    /// (an older model folder: `visage models fetch` adds it); a corrupt file is still an error.
    pub fn load_full_range_if_present(models: &Path) -> Result<Option<Self>, FaceError> {
        match Self::load_full_range(models) {
            Ok(d) => Ok(Some(d)),
            Err(FaceError::ModelMissing { .. }) => Ok(None),
            Err(e) => Err(e),
        }
    }

    /// Loads and verifies `model`'s file from the model directory, with its default options
    /// ([`DetectorOptions::for_model`]).
    pub fn load_model(model: DetectorModel, models: &Path) -> Result<Self, FaceError> {
        Self::from_model_bytes(model, &model.model_file().read(models)?)
    }

    /// Compiles the short-range detector from the bytes of `face_detection_short_range.tflite`.
    pub fn from_bytes(bytes: &[u8]) -> Result<Self, FaceError> {
        Self::from_model_bytes(DetectorModel::ShortRange, bytes)
    }

    /// Compiles `model` from the bytes of its file; checks the input shape and the outputs.
    pub fn from_model_bytes(model: DetectorModel, bytes: &[u8]) -> Result<Self, FaceError> {
        let name = model.model_file().file_name();
        let net = Network::from_tflite(bytes, name)?;
        let bad = |reason: String| FaceError::Tflite {
            name: name.into(),
            reason,
        };
        let (side, n) = (model.input_size(), model.num_anchors());
        if net.input_shape() != [1, side, side, 3] {
            return Err(bad(format!("input shape {:?}", net.input_shape())));
        }
        let [reg, cls] = model.output_names();
        if net.output_named(reg).map(<[f32]>::len) != Some(n * 16)
            || net.output_named(cls).map(<[f32]>::len) != Some(n)
        {
            return Err(bad(format!(
                "outputs are not {reg} [1,{n},16] and {cls} [1,{n},1]"
            )));
        }
        Ok(FaceDetector {
            model,
            net,
            anchors: model.anchors(),
            options: DetectorOptions::for_model(model),
            input_rgb: Vec::new(),
        })
    }

    /// The network this detector runs.
    pub fn model(&self) -> DetectorModel {
        self.model
    }

    /// Runs the network on an RGB8 input of the model's size (128×128 or 192×192, row-major,
    /// 3 bytes per pixel) and decodes every anchor (no threshold, no NMS), coordinates
    /// normalised to the input square.
    pub fn run_rgb8(&mut self, rgb: &[u8]) -> Result<Vec<Detection>, FaceError> {
        let input = self.net.input_mut();
        if rgb.len() != input.len() {
            return Err(FaceError::InputSize {
                what: "detector input",
                expected: input.len(),
                found: rgb.len(),
            });
        }
        for (t, &v) in input.iter_mut().zip(rgb) {
            *t = v as f32 / 127.5 - 1.0;
        }
        self.net.run();
        Ok(self.decode_all())
    }

    /// The raw outputs of the last run: regressors `[N, 16]` and classificator logits `[N]`.
    pub fn raw_outputs(&self) -> (&[f32], &[f32]) {
        let [reg, cls] = self.model.output_names();
        (
            self.net.output_named(reg).unwrap_or(&[]),
            self.net.output_named(cls).unwrap_or(&[]),
        )
    }

    /// Decodes the current outputs (`s` = input side, 128 or 192): `cx = r0/s + ax`,
    /// `cy = r1/s + ay`, `w = r2/s`, `h = r3/s`, keypoint `k` = `(r[4+2k]/s + ax, r[5+2k]/s + ay)`,
    /// score = sigmoid.
    fn decode_all(&self) -> Vec<Detection> {
        let (reg, cls) = self.raw_outputs();
        let s = self.model.input_size() as f32;
        self.anchors
            .iter()
            .zip(reg.chunks_exact(16))
            .zip(cls)
            .map(|((a, r), &logit)| Detection {
                score: sigmoid(logit),
                center: [r[0] / s + a[0], r[1] / s + a[1]],
                size: [r[2] / s, r[3] / s],
                keypoints: std::array::from_fn(|k| {
                    [r[4 + 2 * k] / s + a[0], r[5 + 2 * k] / s + a[1]]
                }),
            })
            .collect()
    }

    /// Detects faces in a frame: letter-box, network, threshold, weighted NMS. Detections are in
    /// frame pixels with MediaPipe's convention (pixel `(i, j)` covers `[i, i+1) × [j, j+1)`),
    /// highest score first. A frame with no face gives an empty list.
    pub fn detect(&mut self, image: &RgbImage) -> Result<Vec<Detection>, FaceError> {
        if image.width() == 0 || image.height() == 0 {
            return Err(FaceError::Image {
                reason: format!("empty image {}×{}", image.width(), image.height()),
            });
        }
        let mut rgb = std::mem::take(&mut self.input_rgb);
        let side = self.model.input_size();
        let lb: Letterbox = match self.options.resize {
            ResizeFilter::Area => letterbox_resize(image, side, &mut rgb),
            ResizeFilter::Bilinear => letterbox_bilinear(image, side, &mut rgb),
        };
        let all = self.run_rgb8(&rgb);
        self.input_rgb = rgb;
        let candidates = all?
            .into_iter()
            .filter(|d| d.score >= self.options.score_threshold)
            .collect();
        let s = lb.side as f32;
        Ok(weighted_nms(candidates, self.options.iou_threshold)
            .into_iter()
            .map(|d| d.map([s, s], [-(lb.offset_x as f32), -(lb.offset_y as f32)]))
            .collect())
    }

    /// Detects faces in the whole frame ([`FaceDetector::detect`]) and in each square tile of
    /// side `tile` ([`tiles`]), then merges them all by weighted NMS: a visage extension for faces
    /// too small for one pass over the frame. On a whole frame a face must cover about 10 of the
    /// network's input pixels (MediaPipe's full-range model on 1280×720: faces from ~70 px wide),
    /// so tiles of side `tile` find faces from about `tile / 16` px (640-px tiles of a 1280×720
    /// frame: ~40 px). Costs one network run per tile more (6 for 640-px tiles of 1280×720);
    /// with `tile` ≥ both sides it is [`FaceDetector::detect`].
    pub fn detect_tiled(
        &mut self,
        image: &RgbImage,
        tile: u32,
    ) -> Result<Vec<Detection>, FaceError> {
        let mut all = self.detect(image)?;
        let rects = tiles(image.width(), image.height(), tile);
        if rects.len() > 1 {
            for [x, y, w, h] in rects {
                let crop = image::imageops::crop_imm(image, x, y, w, h).to_image();
                all.extend(
                    self.detect(&crop)?
                        .into_iter()
                        .map(|d| d.map([1.0, 1.0], [x as f32, y as f32])),
                );
            }
            all = weighted_nms(all, self.options.iou_threshold);
        }
        Ok(all)
    }
}

/// The tiles [`FaceDetector::detect_tiled`] cuts a `width × height` frame into, as
/// `[x, y, w, h]`, row by row: along each axis one tile when the side fits in `tile`, else the
/// fewest tiles of side `tile` that overlap by at least a quarter tile, spread evenly (origins
/// `i·(side − tile) / (n − 1)`, rounded down). A zero `tile` gives one tile, the whole frame.
pub fn tiles(width: u32, height: u32, tile: u32) -> Vec<[u32; 4]> {
    let axis = |side: u32| -> Vec<(u32, u32)> {
        if side <= tile || tile == 0 {
            return vec![(0, side)];
        }
        let step = tile - tile / 4;
        let n = (side - tile).div_ceil(step) + 1;
        (0..n)
            .map(|i| {
                (
                    (i as u64 * (side - tile) as u64 / (n - 1) as u64) as u32,
                    tile,
                )
            })
            .collect()
    };
    let (xs, ys) = (axis(width), axis(height));
    ys.iter()
        .flat_map(|&(y, h)| xs.iter().map(move |&(x, w)| [x, y, w, h]))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tiles_cover_the_frame_with_overlap() {
        assert_eq!(
            tiles(1280, 720, 640),
            [
                [0, 0, 640, 640],
                [320, 0, 640, 640],
                [640, 0, 640, 640],
                [0, 80, 640, 640],
                [320, 80, 640, 640],
                [640, 80, 640, 640],
            ]
        );
        assert_eq!(tiles(500, 300, 640), [[0, 0, 500, 300]]);
        assert_eq!(tiles(500, 300, 0), [[0, 0, 500, 300]]);
        for (w, h, t) in [
            (1920, 1080, 640),
            (1281, 641, 640),
            (7, 5, 2),
            (100, 100, 3),
        ] {
            let rects = tiles(w, h, t);
            for r in &rects {
                assert!(r[0] + r[2] <= w && r[1] + r[3] <= h, "{r:?} in {w}×{h}");
            }
            // Every pixel column and row is covered, neighbours overlap by ≥ tile / 4.
            let xs: Vec<_> = rects.iter().filter(|r| r[1] == 0).collect();
            assert_eq!((xs[0][0], xs.last().map(|r| r[0] + r[2])), (0, Some(w)));
            for p in xs.windows(2) {
                assert!(p[0][0] + p[0][2] >= p[1][0] + t / 4, "{p:?}");
            }
        }
    }

    #[test]
    fn model_constants() {
        let short = DetectorModel::ShortRange;
        let full = DetectorModel::FullRange;
        assert_eq!((short.input_size(), short.num_anchors()), (128, 896));
        assert_eq!((full.input_size(), full.num_anchors()), (192, 2304));
        assert_eq!(full.anchors().len(), 2304);
        assert_eq!(
            (short.score_threshold(), full.score_threshold()),
            (0.5, 0.6)
        );
        assert_eq!(
            DetectorOptions::default(),
            DetectorOptions::for_model(short)
        );
        assert_eq!(
            full.model_file().file_name(),
            "face_detection_full_range_sparse.tflite"
        );
    }
}
