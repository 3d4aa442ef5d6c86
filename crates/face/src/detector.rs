//! BlazeFace short-range face detector (`face_detection_short_range.tflite`), MediaPipe's
//! `face_detection_short_range_cpu` graph: letter-box to 128×128, RGB in [−1, 1], decode the
//! 896 SSD anchors, sigmoid scores, threshold, weighted NMS, remove the letter-box.

use std::path::Path;

use image::RgbImage;

use crate::anchors::{blazeface_anchors, DETECTOR_INPUT, NUM_ANCHORS};
use crate::letterbox::{letterbox_bilinear, letterbox_resize, Letterbox};
use crate::nms::{weighted_nms, NMS_IOU_THRESHOLD};
use crate::{sigmoid, Detection, FaceError, ModelFile, Network};

/// Minimum face score MediaPipe's face detection keeps (`min_score_thresh`).
pub const DETECTION_SCORE_THRESHOLD: f32 = 0.5;

/// Detector options.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DetectorOptions {
    /// Detections with a lower score are dropped ([`DETECTION_SCORE_THRESHOLD`]).
    pub score_threshold: f32,
    /// IoU above which weighted NMS merges detections ([`NMS_IOU_THRESHOLD`]).
    pub iou_threshold: f32,
    /// How the frame is resized into the 128×128 input.
    pub resize: ResizeFilter,
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
    fn default() -> Self {
        DetectorOptions {
            score_threshold: DETECTION_SCORE_THRESHOLD,
            iou_threshold: NMS_IOU_THRESHOLD,
            resize: ResizeFilter::default(),
        }
    }
}

/// The compiled detector with its anchors and buffers.
#[derive(Clone, Debug)]
pub struct FaceDetector {
    net: Network,
    anchors: Vec<[f32; 2]>,
    /// Options used by [`FaceDetector::detect`].
    pub options: DetectorOptions,
    input_rgb: Vec<u8>,
}

impl FaceDetector {
    /// Loads and verifies `face_detection_short_range.tflite` from the model directory.
    pub fn load(models: &Path) -> Result<Self, FaceError> {
        Self::from_bytes(&ModelFile::FaceDetectionShortRange.read(models)?)
    }

    /// Compiles the detector from the bytes of `face_detection_short_range.tflite`.
    pub fn from_bytes(bytes: &[u8]) -> Result<Self, FaceError> {
        let name = ModelFile::FaceDetectionShortRange.file_name();
        let net = Network::from_tflite(bytes, name)?;
        let bad = |reason: String| FaceError::Tflite {
            name: name.into(),
            reason,
        };
        if net.input_shape() != [1, DETECTOR_INPUT, DETECTOR_INPUT, 3] {
            return Err(bad(format!("input shape {:?}", net.input_shape())));
        }
        if net.output_named("regressors").map(<[f32]>::len) != Some(NUM_ANCHORS * 16)
            || net.output_named("classificators").map(<[f32]>::len) != Some(NUM_ANCHORS)
        {
            return Err(bad(
                "outputs are not regressors [1,896,16] and classificators [1,896,1]".into(),
            ));
        }
        Ok(FaceDetector {
            net,
            anchors: blazeface_anchors(),
            options: DetectorOptions::default(),
            input_rgb: Vec::new(),
        })
    }

    /// Runs the network on a 128×128 RGB8 input (row-major, 3 bytes per pixel) and decodes
    /// every anchor (no threshold, no NMS), coordinates normalised to the input square.
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

    /// Decodes the current outputs: `cx = r0/128 + ax`, `cy = r1/128 + ay`, `w = r2/128`,
    /// `h = r3/128`, keypoint `k` = `(r[4+2k]/128 + ax, r[5+2k]/128 + ay)`, score = sigmoid.
    fn decode_all(&self) -> Vec<Detection> {
        let reg = self.net.output_named("regressors").unwrap_or(&[]);
        let cls = self.net.output_named("classificators").unwrap_or(&[]);
        let s = DETECTOR_INPUT as f32;
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
        let lb: Letterbox = match self.options.resize {
            ResizeFilter::Area => letterbox_resize(image, DETECTOR_INPUT, &mut rgb),
            ResizeFilter::Bilinear => letterbox_bilinear(image, DETECTOR_INPUT, &mut rgb),
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
}
