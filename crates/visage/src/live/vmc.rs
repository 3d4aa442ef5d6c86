//! The VMC protocol (Virtual Motion Capture's OSC messages over UDP, what VSeeFace, Warudo,
//! VNyan, VMagicMirror and VTube Studio's plug-ins receive): per frame `/VMC/Ext/OK 1` (a
//! model is loaded), `/VMC/Ext/T` (seconds), the 52 ARKit weights as `/VMC/Ext/Blend/Val`
//! with ARKit's own names (`jawOpen`, `eyeBlinkLeft`: what "perfect sync" avatars' clips are
//! named), then `/VMC/Ext/Blend/Apply`. A frame without a face sends only the first two, so
//! the avatar holds its last expression. Bundles are kept under 1,200 bytes (one Ethernet
//! frame); the last one carries `Apply`.

use std::net::{ToSocketAddrs, UdpSocket};

use visage_rig::ARKIT_BLENDSHAPES;

use super::osc::{bundle, message, Arg};
use super::session::{LiveFrame, LiveSubscriber};

/// Largest bundle sent, bytes.
const MAX_DATAGRAM: usize = 1200;

/// Sends each frame to a VMC receiver.
pub struct VmcSender {
    socket: UdpSocket,
    target: String,
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
        })
    }

    /// The datagrams of one frame.
    fn datagrams(frame: &LiveFrame<'_>) -> Vec<Vec<u8>> {
        let mut messages = vec![
            message("/VMC/Ext/OK", &[Arg::Int(1)]),
            message("/VMC/Ext/T", &[Arg::Float(frame.time_s as f32)]),
        ];
        if let Some(b) = frame.result.blendshapes {
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
        for d in Self::datagrams(frame) {
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
