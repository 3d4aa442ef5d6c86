//! Live capture: a source read as it arrives ([`visage_video::LiveCapture`]: the newest frame
//! wins), each frame processed causally by a [`crate::Reconstructor`] and handed to the
//! session's subscribers — the streams out — the moment it is done, with the latency from its
//! capture to the subscribers' return measured per frame ([`LiveSession`]). The streams:
//! the VMC protocol over OSC ([`VmcSender`]) and Live Link Face's UDP packet
//! ([`LiveLinkFaceSender`], Unreal's Live Link), and a local web page showing the face as it
//! moves ([`LivePage`]: HTTP and a WebSocket on the address the user names). A session can
//! also be recorded into the folder `visage run` writes ([`LiveRecording`]).

mod live_link_face;
mod live_page;
mod osc;
mod recording;
mod session;
mod vmc;

pub use live_link_face::{unreal_order, LiveLinkFaceSender, DEFAULT_DEVICE_ID};
pub use live_page::{LivePage, FRAME_HEADER, SOCKET_PATH};
pub use recording::LiveRecording;
pub use session::{LatencyFigures, LiveFrame, LiveSession, LiveSubscriber, LiveSummary};
pub use vmc::VmcSender;
