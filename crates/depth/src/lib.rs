//! Per-pixel depth from the sources users have (paper §2: "a pretrained CNN P_d … produces,
//! for every frame, a dense depth map D_k"), each a [`DepthProvider`] — the pipeline's one
//! interface to them:
//! - **ONNX depth networks** the user supplies ([`DepthNetwork`], run by `tract`, pure Rust),
//!   described by a small JSON file beside them ([`NetworkConfig`]: input size, colour order,
//!   normalisation, what the output means). Outputs known only up to a scale and shift per
//!   frame — relative depth, inverse depth, disparity — are aligned to the metric face by a
//!   robust fit in their own space ([`align`]); [`AlignedNetwork`] is the two as a provider.
//! - **Depth folders** ([`DepthSequence`]): 16-bit PNG maps, one per frame in name order.
//! - **RGB-D recordings** ([`RgbdRecording`]): the TUM RGB-D layout or a pair of `rgb/` and
//!   `depth/` folders, colour and depth associated by timestamp, depth registered to the
//!   colour camera, holes and flying pixels at depth edges masked.
//!
//! Depth maps are [`visage_camera::DepthMap`]s in metres.

#![forbid(unsafe_code)]

mod aligned_network;
mod alignment;
mod depth_edges;
mod depth_network;
mod depth_provider;
mod depth_sequence;
mod error;
mod network_config;
mod prediction;
mod registration;
mod rgbd_recording;

pub use aligned_network::AlignedNetwork;
pub use alignment::{align, Alignment, AlignmentFailure, AlignmentOptions};
pub use depth_edges::{mask_depth_edges, EdgeMask};
pub use depth_network::DepthNetwork;
pub use depth_provider::{DepthProvider, DepthRequest, ProvidedDepth};
pub use depth_sequence::DepthSequence;
pub use error::DepthError;
pub use network_config::{
    AlignMode, ColorOrder, InputSpec, Layout, NetworkConfig, NetworkRegion, OutputKind, OutputSpec,
    Resize, DEFAULT_FACE_MARGIN, IMAGENET_MEAN, IMAGENET_STD,
};
pub use prediction::{FrameRegion, Prediction};
pub use registration::Registration;
pub use rgbd_recording::{
    parse_tum_list, RgbdFrame, RgbdLayout, RgbdOptions, RgbdRecording, FOLDER_DEPTH_SCALE,
    MAX_TIME_DIFFERENCE_S, TUM_DEPTH_SCALE,
};
