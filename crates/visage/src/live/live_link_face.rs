//! Live Link Face's UDP packet — what Unreal Engine's Live Link receives from the iPhone app
//! (default port 11111): `u8` version 6, the device id and the subject name (each an `i32`
//! length and UTF-8 bytes), the frame time (`i32` frame and `f32` sub-frame at the rate that
//! follows, `i32` numerator and denominator: 60/1), then `u8` 61 and 61 `f32` values — the 52
//! blendshapes in Unreal's `EARFaceBlendShape` order (`JawLeft` before `JawRight`,
//! `MouthLeft` before `MouthRight`, unlike the app's CSV columns), then head and eyes' yaw,
//! pitch and roll in radians. Every number big-endian. A frame without a face sends nothing, so
//! the subject holds its last pose. The frame time is the capture's time of day (UTC).
//! Checked against the PyPI package `pylivelinkface`, which decodes the app's packets.

use std::net::{ToSocketAddrs, UdpSocket};
use std::time::{SystemTime, UNIX_EPOCH};

use visage_rig::{ARKIT_BLENDSHAPES, LIVE_LINK_VALUE_COUNT};

use super::session::{LiveFrame, LiveSubscriber};

/// Unreal's `EARFaceBlendShape` order of the 52 blendshapes, by ARKit name.
pub const UNREAL_ORDER: [&str; 52] = [
    "eyeBlinkLeft",
    "eyeLookDownLeft",
    "eyeLookInLeft",
    "eyeLookOutLeft",
    "eyeLookUpLeft",
    "eyeSquintLeft",
    "eyeWideLeft",
    "eyeBlinkRight",
    "eyeLookDownRight",
    "eyeLookInRight",
    "eyeLookOutRight",
    "eyeLookUpRight",
    "eyeSquintRight",
    "eyeWideRight",
    "jawForward",
    "jawLeft",
    "jawRight",
    "jawOpen",
    "mouthClose",
    "mouthFunnel",
    "mouthPucker",
    "mouthLeft",
    "mouthRight",
    "mouthSmileLeft",
    "mouthSmileRight",
    "mouthFrownLeft",
    "mouthFrownRight",
    "mouthDimpleLeft",
    "mouthDimpleRight",
    "mouthStretchLeft",
    "mouthStretchRight",
    "mouthRollLower",
    "mouthRollUpper",
    "mouthShrugLower",
    "mouthShrugUpper",
    "mouthPressLeft",
    "mouthPressRight",
    "mouthLowerDownLeft",
    "mouthLowerDownRight",
    "mouthUpperUpLeft",
    "mouthUpperUpRight",
    "browDownLeft",
    "browDownRight",
    "browInnerUp",
    "browOuterUpLeft",
    "browOuterUpRight",
    "cheekPuff",
    "cheekSquintLeft",
    "cheekSquintRight",
    "noseSneerLeft",
    "noseSneerRight",
    "tongueOut",
];

/// The packet version the app sends.
const VERSION: u8 = 6;

/// The timecode rate of the frame time.
const RATE: i32 = 60;

/// The device id sent when none is given: a UUID's shape (36 characters), as the app sends.
pub const DEFAULT_DEVICE_ID: &str = "76697361-6765-4c69-7665-4c696e6b4661";

/// Sends each frame with a face to a Live Link receiver (Unreal's Live Link Face source).
pub struct LiveLinkFaceSender {
    socket: UdpSocket,
    target: String,
    device_id: String,
    subject: String,
    /// `ARKIT_BLENDSHAPES`' index of each `UNREAL_ORDER` name.
    order: [usize; 52],
}

impl LiveLinkFaceSender {
    /// A sender to `target` (`host:port`; Unreal listens on 11111) under the subject name
    /// `subject` and the device id `device_id`.
    ///
    /// # Errors
    /// The address does not resolve, or no UDP socket can be opened.
    pub fn new(target: &str, subject: &str, device_id: &str) -> std::io::Result<Self> {
        let address = target.to_socket_addrs()?.next().ok_or_else(|| {
            std::io::Error::new(std::io::ErrorKind::NotFound, "no address for it")
        })?;
        let socket = UdpSocket::bind(if address.is_ipv4() {
            "0.0.0.0:0"
        } else {
            "[::]:0"
        })?;
        socket.connect(address)?;
        let order = std::array::from_fn(|i| {
            ARKIT_BLENDSHAPES
                .iter()
                .position(|n| *n == UNREAL_ORDER[i])
                .expect("the same 52 names")
        });
        Ok(LiveLinkFaceSender {
            socket,
            target: target.to_owned(),
            device_id: device_id.to_owned(),
            subject: subject.to_owned(),
            order,
        })
    }

    /// The packet of one frame's values (`values`: the 52 weights in `ARKIT_BLENDSHAPES`'
    /// order, then the 9 angles) at `seconds` of the day.
    fn packet(&self, values: &[f32; LIVE_LINK_VALUE_COUNT], seconds: f64) -> Vec<u8> {
        let mut out = Vec::with_capacity(64 + 4 * LIVE_LINK_VALUE_COUNT);
        out.push(VERSION);
        for text in [&self.device_id, &self.subject] {
            out.extend_from_slice(&(text.len() as i32).to_be_bytes());
            out.extend_from_slice(text.as_bytes());
        }
        let frames = seconds * f64::from(RATE);
        out.extend_from_slice(&(frames.floor() as i32).to_be_bytes());
        out.extend_from_slice(&(frames.fract() as f32).to_be_bytes());
        out.extend_from_slice(&RATE.to_be_bytes());
        out.extend_from_slice(&1i32.to_be_bytes());
        out.push(LIVE_LINK_VALUE_COUNT as u8);
        for &i in &self.order {
            out.extend_from_slice(&values[i].to_be_bytes());
        }
        for v in &values[52..] {
            out.extend_from_slice(&v.to_be_bytes());
        }
        out
    }
}

impl LiveSubscriber for LiveLinkFaceSender {
    fn frame(&mut self, frame: &LiveFrame<'_>) -> std::io::Result<()> {
        let Some(b) = frame.result.blendshapes else {
            return Ok(());
        };
        let now = SystemTime::now()
            .duration_since(UNIX_EPOCH)
            .map_or(0.0, |d| d.as_secs_f64());
        let captured = now - frame.captured_at.elapsed().as_secs_f64();
        let packet = self.packet(&b.live_link_values(), captured.rem_euclid(86_400.0));
        match self.socket.send(&packet) {
            // Nobody listening (yet): Unreal may start after the sender.
            Err(e) if e.kind() == std::io::ErrorKind::ConnectionRefused => Ok(()),
            other => other.map(drop),
        }
    }

    fn describe(&self) -> String {
        format!("Live Link Face to {} as {:?}", self.target, self.subject)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_packet_has_the_apps_layout() {
        let s = LiveLinkFaceSender::new("127.0.0.1:9", "visage", DEFAULT_DEVICE_ID).unwrap();
        let mut values = [0.0f32; LIVE_LINK_VALUE_COUNT];
        let jaw_left = ARKIT_BLENDSHAPES
            .iter()
            .position(|n| *n == "jawLeft")
            .unwrap();
        values[jaw_left] = 0.5;
        values[52] = 0.25;
        let p = s.packet(&values, 3661.5);
        assert_eq!(p[0], 6);
        assert_eq!(&p[1..5], &36i32.to_be_bytes());
        assert_eq!(&p[5..41], DEFAULT_DEVICE_ID.as_bytes());
        assert_eq!(&p[41..45], &6i32.to_be_bytes());
        assert_eq!(&p[45..51], b"visage");
        assert_eq!(&p[51..55], &(3661 * 60 + 30i32).to_be_bytes());
        assert_eq!(&p[63..67], &1i32.to_be_bytes());
        assert_eq!(p[67], 61);
        let value = |k: usize| f32::from_be_bytes(p[68 + 4 * k..72 + 4 * k].try_into().unwrap());
        assert_eq!(value(15), 0.5, "JawLeft is Unreal's 16th value");
        assert_eq!(value(52), 0.25, "then the head's yaw");
        assert_eq!(p.len(), 68 + 4 * 61);
    }
}
