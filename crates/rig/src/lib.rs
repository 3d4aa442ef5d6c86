//! The face rig: what a fitted face means to an animator. From the per-frame fit of the
//! morphable model (ICT-FaceKit's expressions, `visage-morphable`) and the irises, it makes
//! the 52 ARKit blendshape weights ([`IctToArkit`], its name tables), the eyes'
//! rotations ([`eye_gaze`], held through blinks by the [`LidGate`]), the lids from the eye
//! network's contour ([`Eyelids`]: blink and wide eyes), measured from the person's resting
//! face ([`RestPose`]) less what the head's turn alone adds ([`PoseLeak`]) and what the
//! mouth's shapes alone add to the upper face's ([`MouthLeak`]), and the head's rotation, as
//! one [`BlendshapeFrame`] per frame with Live Link Face's names and signs.

#![forbid(unsafe_code)]

mod arkit;
mod blendshape_frame;
mod eye_rig;
mod eyelids;
mod gaze;
mod histogram;
mod lid_gate;
mod mouth_leak;
mod pose_leak;
mod rest_pose;

pub use arkit::{
    ArkitToIct, IctSource, IctToArkit, ARKIT_BLENDSHAPES, ARKIT_BLENDSHAPE_COUNT, ICT_EXPRESSIONS,
    ICT_TO_ARKIT,
};
pub use blendshape_frame::{
    live_link_angles, live_link_rotation, BlendshapeFrame, BlendshapeTrack, LIVE_LINK_BLENDSHAPES,
    LIVE_LINK_ROTATIONS, LIVE_LINK_VALUE_COUNT,
};
pub use eye_rig::{
    EyeObservation, EyeRig, FAR_EYE_FROM_DEG, FAR_EYE_FULL_DEG, WINK_NEAR, WINK_OPENNESS,
    WINK_UPPER,
};
pub use eyelids::{
    closed_aperture, opening, upper_lid_seen, Eyelids, LidOpening, LidPoints, LidReading,
    CLOSED_APERTURE, CLOSED_PER_PITCH_BELOW, MIN_OPEN_APERTURE, OPEN_EDGE, OPEN_QUANTILE,
    UPPER_CLOSED, UPPER_OPEN_EDGE, UPPER_PER_PITCH, UPPER_PER_YAW, WIDE_EDGE, WIDE_FULL,
};
pub use gaze::{
    eye_gaze, eye_look_gaze, eye_look_weights, EyeGaze, CONTOUR_CORNERS_OFFSET_M, EYEBALL_DEPTH_M,
    EYE_LOOK_FULL_RAD, IRIS_ROTATION_RADIUS_M,
};
pub use lid_gate::{LidGate, HOLD_BLINK};
pub use mouth_leak::{is_mouth, is_upper_face, MouthLeak};
pub use pose_leak::{pose_leak_terms, LeakLearning, LeakSample, PoseLeak, POSE_LEAK_TERMS};
pub use rest_pose::{lips_closed, RestPose, CLOSED_LIP_GAP, MIN_RANGE};
