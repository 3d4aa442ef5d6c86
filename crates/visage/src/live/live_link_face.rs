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

/// Where Unreal's `EARFaceBlendShape` order differs from [`ARKIT_BLENDSHAPES`]' (the app's
/// CSV columns): each pair of names swaps places, the rest keep theirs.
const UNREAL_SWAPS: [(&str, &str); 2] = [("jawRight", "jawLeft"), ("mouthRight", "mouthLeft")];

/// `ARKIT_BLENDSHAPES`' index of each of Unreal's 52 blendshapes, in Unreal's order.
pub fn unreal_order() -> [usize; 52] {
    let index = |name: &str| {
        ARKIT_BLENDSHAPES
            .iter()
            .position(|n| *n == name)
            .expect("an ARKit name")
    };
    let mut order: [usize; 52] = std::array::from_fn(|i| i);
    for (a, b) in UNREAL_SWAPS {
        order.swap(index(a), index(b));
    }
    order
}

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
    /// [`unreal_order`].
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
        let order = unreal_order();
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
        let names: Vec<&str> = unreal_order()
            .iter()
            .map(|&i| ARKIT_BLENDSHAPES[i])
            .collect();
        assert_eq!(
            &names[14..18],
            ["jawForward", "jawLeft", "jawRight", "jawOpen"]
        );
        assert_eq!(&names[21..23], ["mouthLeft", "mouthRight"]);
        assert_eq!(value(52), 0.25, "then the head's yaw");
        assert_eq!(p.len(), 68 + 4 * 61);
    }
}
