//! The VMC protocol (Virtual Motion Capture's OSC messages over UDP, what VSeeFace, Warudo,
//! VNyan, VMagicMirror and VTube Studio's plug-ins receive): per frame `/VMC/Ext/OK 1` (a
//! model is loaded), `/VMC/Ext/T` (seconds), the 52 ARKit weights as `/VMC/Ext/Blend/Val`
//! with ARKit's own names (`jawOpen`, `eyeBlinkLeft`: what "perfect sync" avatars' clips are
//! named), then `/VMC/Ext/Blend/Apply`. A frame without a face sends only the first two, so
//! the avatar holds its last expression. Bundles are kept under 1,200 bytes (one Ethernet
//! frame); the last one carries `Apply`.
//!
//! With bones on ([`VmcSender::with_bones`]), each frame with a face also sends, before its
//! weights, the `Head`,
//! `LeftEye` and `RightEye` bones (`/VMC/Ext/Bone/Pos`, Unity's humanoid names) as local
//! rotations in Unity's frame — left-handed, x to the avatar's right, y up, z the way it faces
//! —: the head relative to facing the camera, each eye relative to the head, the subject's own
//! sides (no mirroring, as ARKit's weights: `eyeBlinkLeft` is the subject's left eye). A head
//! turned to the subject's right is a positive rotation about y, looking down a positive one
//! about x, the top tilted toward the right shoulder a negative one about z (Unity's
//! `Quaternion.Euler` order, z then x then y). The bone position sent is 0: a sender does not
//! know the avatar's proportions, so a receiver must take only the rotation from it.

use std::net::{ToSocketAddrs, UdpSocket};

use visage_rig::{live_link_rotation, ARKIT_BLENDSHAPES};

use super::osc::{bundle, message, Arg};
use super::session::{LiveFrame, LiveSubscriber};

/// Largest bundle sent, bytes.
const MAX_DATAGRAM: usize = 1200;

/// Sends each frame to a VMC receiver.
pub struct VmcSender {
    socket: UdpSocket,
    target: String,
    bones: bool,
}

impl VmcSender {
    /// A sender to `target` (`host:port`; VSeeFace and most receivers listen on 39539).
    ///
    /// # Errors
    /// The address does not resolve, or no UDP socket can be opened.
    pub fn new(target: &str) -> std::io::Result<VmcSender> {
        let address = target.to_socket_addrs()?.next().ok_or_else(|| {
            std::io::Error::new(std::io::ErrorKind::NotFound, "no address for it")
        })?;
        let local = if address.is_ipv4() {
            "0.0.0.0:0"
        } else {
            "[::]:0"
        };
        let socket = UdpSocket::bind(local)?;
        socket.connect(address)?;
        Ok(VmcSender {
            socket,
            target: target.to_owned(),
            bones: false,
        })
    }

    /// Also sends the head's and the eyes' rotations as bones (the module's docs).
    pub fn with_bones(mut self, on: bool) -> VmcSender {
        self.bones = on;
        self
    }

    /// The datagrams of one frame.
    fn datagrams(&self, frame: &LiveFrame<'_>) -> Vec<Vec<u8>> {
        let mut messages = vec![
            message("/VMC/Ext/OK", &[Arg::Int(1)]),
            message("/VMC/Ext/T", &[Arg::Float(frame.time_s as f32)]),
        ];
        if let Some(b) = frame.result.blendshapes {
            if self.bones {
                for (bone, angles) in [
                    ("Head", b.head),
                    ("LeftEye", b.left_eye),
                    ("RightEye", b.right_eye),
                ] {
                    let [x, y, z, w] = unity_rotation(angles);
                    let zero = Arg::Float(0.0);
                    messages.push(message(
                        "/VMC/Ext/Bone/Pos",
                        &[
                            Arg::Str(bone),
                            zero.clone(),
                            zero.clone(),
                            zero,
                            Arg::Float(x),
                            Arg::Float(y),
                            Arg::Float(z),
                            Arg::Float(w),
                        ],
                    ));
                }
            }
            for (name, &w) in ARKIT_BLENDSHAPES.iter().zip(&b.weights) {
                messages.push(message(
                    "/VMC/Ext/Blend/Val",
                    &[Arg::Str(name), Arg::Float(w)],
                ));
            }
            messages.push(message("/VMC/Ext/Blend/Apply", &[]));
        }
        let mut datagrams = Vec::new();
        let mut batch: Vec<&[u8]> = Vec::new();
        let mut size = 16;
        for m in &messages {
            if size + 4 + m.len() > MAX_DATAGRAM && !batch.is_empty() {
                datagrams.push(bundle(batch.drain(..)));
                size = 16;
            }
            size += 4 + m.len();
            batch.push(m);
        }
        datagrams.push(bundle(batch));
        datagrams
    }
}

impl LiveSubscriber for VmcSender {
    fn frame(&mut self, frame: &LiveFrame<'_>) -> std::io::Result<()> {
        for d in self.datagrams(frame) {
            match self.socket.send(&d) {
                // Nobody listening (yet): a receiver may start after the sender.
                Err(e) if e.kind() == std::io::ErrorKind::ConnectionRefused => {}
                other => {
                    other?;
                }
            }
        }
        Ok(())
    }

    fn describe(&self) -> String {
        format!("VMC to {}", self.target)
    }
}

/// Live Link Face's `[yaw, pitch, roll]` as a quaternion `[x, y, z, w]` in Unity's frame (the
/// module's docs): the face frame's rotation (x to the subject's left, right-handed) seen with
/// x turned to the avatar's right, `S R S` with `S = diag(−1, 1, 1)`.
pub fn unity_rotation(angles: [f32; 3]) -> [f32; 4] {
    let r = live_link_rotation(angles.map(f64::from));
    let sign = [-1.0, 1.0, 1.0];
    let m: [[f64; 3]; 3] =
        std::array::from_fn(|i| std::array::from_fn(|j| sign[i] * r[i][j] * sign[j]));
    let trace = m[0][0] + m[1][1] + m[2][2];
    let q = if trace > 0.0 {
        let s = 0.5 / (trace + 1.0).sqrt();
        [
            (m[2][1] - m[1][2]) * s,
            (m[0][2] - m[2][0]) * s,
            (m[1][0] - m[0][1]) * s,
            0.25 / s,
        ]
    } else if m[0][0] > m[1][1] && m[0][0] > m[2][2] {
        let s = 2.0 * (1.0 + m[0][0] - m[1][1] - m[2][2]).sqrt();
        [
            0.25 * s,
            (m[0][1] + m[1][0]) / s,
            (m[0][2] + m[2][0]) / s,
            (m[2][1] - m[1][2]) / s,
        ]
    } else if m[1][1] > m[2][2] {
        let s = 2.0 * (1.0 + m[1][1] - m[0][0] - m[2][2]).sqrt();
        [
            (m[0][1] + m[1][0]) / s,
            0.25 * s,
            (m[1][2] + m[2][1]) / s,
            (m[0][2] - m[2][0]) / s,
        ]
    } else {
        let s = 2.0 * (1.0 + m[2][2] - m[0][0] - m[1][1]).sqrt();
        [
            (m[0][2] + m[2][0]) / s,
            (m[1][2] + m[2][1]) / s,
            0.25 * s,
            (m[1][0] - m[0][1]) / s,
        ]
    };
    q.map(|v| v as f32)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Unity's `Quaternion.Euler(x, y, z)` (degrees): z first, then x, then y.
    fn euler(x: f64, y: f64, z: f64) -> [f64; 4] {
        let axis = |a: f64, k: usize| {
            let (s, c) = (a.to_radians() / 2.0).sin_cos();
            let mut q = [0.0, 0.0, 0.0, c];
            q[k] = s;
            q
        };
        let mul = |a: [f64; 4], b: [f64; 4]| {
            [
                a[3] * b[0] + a[0] * b[3] + a[1] * b[2] - a[2] * b[1],
                a[3] * b[1] - a[0] * b[2] + a[1] * b[3] + a[2] * b[0],
                a[3] * b[2] + a[0] * b[1] - a[1] * b[0] + a[2] * b[3],
                a[3] * b[3] - a[0] * b[0] - a[1] * b[1] - a[2] * b[2],
            ]
        };
        mul(mul(axis(y, 1), axis(x, 0)), axis(z, 2))
    }

    #[track_caller]
    fn close(a: [f32; 4], b: [f64; 4]) {
        let same = a
            .iter()
            .zip(&b)
            .all(|(x, y)| (f64::from(*x) - y).abs() < 1e-5);
        let opposite = a
            .iter()
            .zip(&b)
            .all(|(x, y)| (f64::from(*x) + y).abs() < 1e-5);
        assert!(same || opposite, "{a:?} vs {b:?}");
    }

    #[test]
    fn head_angles_become_unitys_rotations_with_the_subjects_sides() {
        let d = |v: f32| v.to_radians();
        // Turned to the subject's right: about +y (forward swings to the avatar's right).
        close(unity_rotation([d(30.0), 0.0, 0.0]), euler(0.0, 30.0, 0.0));
        // Looking down: about +x.
        close(unity_rotation([0.0, d(20.0), 0.0]), euler(20.0, 0.0, 0.0));
        // The top toward the right shoulder: about −z.
        close(unity_rotation([0.0, 0.0, d(10.0)]), euler(0.0, 0.0, -10.0));
        // Together, in Unity's Euler order.
        close(
            unity_rotation([d(25.0), d(-15.0), d(8.0)]),
            euler(-15.0, 25.0, -8.0),
        );
        close(unity_rotation([0.0; 3]), [0.0, 0.0, 0.0, 1.0]);
    }
}
