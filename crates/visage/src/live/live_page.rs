//! The live page: a small HTTP server on the address the user names (`visage live --listen`)
//! that serves one page and its script, and a WebSocket on the same origin through which every
//! processed frame reaches the browsers watching — the face mesh, the head's rotation, the 52
//! ARKit weights, the frame rate and each frame's latency from its capture to the moment its
//! message is written to the socket.
//!
//! What it does not do, on purpose: it serves nothing but its own two files (no folder, no
//! run's outputs), answers only requests whose `Host` is the address it listens on (a page
//! on another site that resolves its own name to 127.0.0.1 gets nothing), and refuses a
//! WebSocket request whose `Origin` is not the page's own (a page on another site cannot
//! watch the camera's face through the visitor's browser). A request without `Origin` comes
//! from no browser (a script); it is served.
//!
//! Each browser gets its own writer thread and a slot of one message, where the newest frame
//! wins: a slow or stalled browser drops frames, never the pipeline.

use std::io::{Read, Write};
use std::net::{SocketAddr, TcpListener, TcpStream, ToSocketAddrs};
use std::sync::{Arc, Condvar, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use tungstenite::{Message, WebSocket};
use visage_rig::{ARKIT_BLENDSHAPES, ARKIT_BLENDSHAPE_COUNT};

use super::session::{LiveFrame, LiveSubscriber};

/// The page (its script is [`LIVE_JS`]).
const PAGE_HTML: &str = include_str!("live_page.html");

/// The page's script (`web/viewer/dist/live.js`, three.js included), when it was built before
/// visage (`web/viewer/build.sh`).
#[cfg(live_page_bundle)]
const LIVE_JS: Option<&str> = Some(include_str!("../../../../web/viewer/dist/live.js"));
#[cfg(not(live_page_bundle))]
const LIVE_JS: Option<&str> = None;

/// The WebSocket's path.
pub const SOCKET_PATH: &str = "/socket";

/// Longest request head read (bytes).
const MAX_HEAD: usize = 16 * 1024;

/// How long a browser may take to send its request, or to take a message.
const IO_TIMEOUT: Duration = Duration::from_secs(5);

/// Numbers before the vertices in a frame message: frame index, seconds, latency, fps, face,
/// yaw, pitch, roll, then the 52 weights.
pub const FRAME_HEADER: usize = 8 + ARKIT_BLENDSHAPE_COUNT;

/// A browser's slot: the mesh's topology when it changed, and the newest frame.
#[derive(Default)]
struct Outbox {
    topology: Option<Arc<String>>,
    frame: Option<(Arc<Vec<u8>>, Instant)>,
    /// Frames replaced before they were sent.
    replaced: usize,
    closed: bool,
}

type Slot = Arc<(Mutex<Outbox>, Condvar)>;

/// What the accepting thread and the session share.
#[derive(Default)]
struct Shared {
    browsers: Vec<Slot>,
    /// The current topology message, sent to each browser before its first frame.
    topology: Option<Arc<String>>,
}

/// The live page, serving on one address; a [`LiveSubscriber`] of a live session.
pub struct LivePage {
    address: SocketAddr,
    shared: Arc<Mutex<Shared>>,
    /// The mesh's vertex and triangle counts the topology message describes.
    topology_of: Option<(usize, usize)>,
    /// When the last frames were sent (for the frame rate over the last second).
    recent: std::collections::VecDeque<Instant>,
    _accept: JoinHandle<()>,
}

impl LivePage {
    /// Listens on `address` (`HOST:PORT`, or a port alone for 127.0.0.1) and serves the page
    /// from a thread of its own.
    ///
    /// # Errors
    /// The address cannot be read or bound.
    pub fn bind(address: &str) -> std::io::Result<LivePage> {
        let target = if address.parse::<u16>().is_ok() {
            format!("127.0.0.1:{address}")
        } else {
            address.to_owned()
        };
        let resolved = target.to_socket_addrs()?.next().ok_or_else(|| {
            std::io::Error::new(std::io::ErrorKind::InvalidInput, "no such address")
        })?;
        let listener = TcpListener::bind(resolved)?;
        let address = listener.local_addr()?;
        let shared = Arc::new(Mutex::new(Shared::default()));
        let accepted = Arc::clone(&shared);
        let accept = std::thread::Builder::new()
            .name("live page".into())
            .spawn(move || {
                for stream in listener.incoming().flatten() {
                    let shared = Arc::clone(&accepted);
                    let _ = std::thread::Builder::new()
                        .name("live page request".into())
                        .spawn(move || serve(stream, address, &shared));
                }
            })?;
        Ok(LivePage {
            address,
            shared,
            topology_of: None,
            recent: std::collections::VecDeque::new(),
            _accept: accept,
        })
    }

    /// The address it listens on (the port chosen when 0 was asked for).
    pub fn address(&self) -> SocketAddr {
        self.address
    }

    /// The page's address, for a browser.
    pub fn url(&self) -> String {
        format!("http://{}/", self.address)
    }

    /// Browsers watching now.
    pub fn browsers(&self) -> usize {
        lock(&self.shared).browsers.len()
    }
}

impl LiveSubscriber for LivePage {
    fn frame(&mut self, frame: &LiveFrame<'_>) -> std::io::Result<()> {
        let now = Instant::now();
        self.recent.push_back(now);
        while self
            .recent
            .front()
            .is_some_and(|t| now.duration_since(*t) > Duration::from_secs(1))
        {
            self.recent.pop_front();
        }
        let mesh = frame.result.mesh();
        let counts = mesh.map(|m| (m.vertices.len(), m.triangles.len()));
        let mut shared = lock(&self.shared);
        if counts.is_some() && counts != self.topology_of {
            self.topology_of = counts;
            let topology = Arc::new(topology_message(mesh.expect("counts come from a mesh")));
            shared.topology = Some(Arc::clone(&topology));
            for browser in &shared.browsers {
                lock_outbox(browser).topology = Some(Arc::clone(&topology));
            }
        }
        if shared.browsers.is_empty() {
            // Nobody watches: no message to make.
            return Ok(());
        }
        let vertices = self.topology_of.map_or(0, |(v, _)| v);
        let message = Arc::new(frame_message(frame, self.recent.len() as f64, vertices));
        shared.browsers.retain(|browser| {
            let mut outbox = lock_outbox(browser);
            if outbox.closed {
                return false;
            }
            if outbox.frame.is_some() {
                outbox.replaced += 1;
            }
            outbox.frame = Some((Arc::clone(&message), frame.captured_at));
            browser.1.notify_one();
            true
        });
        Ok(())
    }

    fn describe(&self) -> String {
        format!("the live page at {}", self.url())
    }
}

impl Drop for LivePage {
    fn drop(&mut self) {
        // The writers end; the accepting thread ends with the process.
        for browser in &lock(&self.shared).browsers {
            lock_outbox(browser).closed = true;
            browser.1.notify_one();
        }
    }
}

/// The mesh's topology and the weights' names, sent before a browser's first frame (JSON).
fn topology_message(mesh: &visage_mesh::TriMesh) -> String {
    serde_json::json!({
        "type": "mesh",
        "vertices": mesh.vertices.len(),
        "triangles": mesh.triangles.iter().flatten().collect::<Vec<_>>(),
        "weights": ARKIT_BLENDSHAPES.as_slice(),
    })
    .to_string()
}

/// One frame as little-endian `f32`s: frame index, seconds since the session started,
/// latency in milliseconds (filled in as it is written to the socket), frames sent in the
/// last second, 1 with a face (else 0), the head's yaw, pitch and roll (radians, Live Link
/// Face's), the 52 weights in ARKit's order, then `vertices` × (x, y, z) in metres, camera
/// coordinates (x right, y down, z forward; zeros without a mesh).
fn frame_message(frame: &LiveFrame<'_>, fps: f64, vertices: usize) -> Vec<u8> {
    let r = frame.result;
    let mut v: Vec<f32> = Vec::with_capacity(FRAME_HEADER + 3 * vertices);
    v.extend([r.index() as f32, frame.time_s as f32, 0.0, fps as f32]);
    match r.blendshapes {
        Some(b) => {
            v.push(1.0);
            v.extend(b.head);
            v.extend(b.weights.iter().copied());
        }
        None => v.extend(std::iter::repeat_n(0.0, 4 + ARKIT_BLENDSHAPE_COUNT)),
    }
    match r.mesh() {
        Some(m) if m.vertices.len() == vertices => {
            v.extend(m.vertices.iter().flatten().map(|&x| x as f32));
        }
        _ => v.extend(std::iter::repeat_n(0.0, 3 * vertices)),
    }
    v.iter().flat_map(|x| x.to_le_bytes()).collect()
}

/// One connection: the page, its script, or the frames' WebSocket.
fn serve(stream: TcpStream, address: SocketAddr, shared: &Mutex<Shared>) {
    let _ = stream.set_read_timeout(Some(IO_TIMEOUT));
    let _ = stream.set_write_timeout(Some(IO_TIMEOUT));
    let Some(head) = peek_head(&stream) else {
        return;
    };
    let request = match Request::parse(&head) {
        Some(r) => r,
        None => return respond(stream, 400, "text/plain", b"bad request"),
    };
    if !host_allowed(request.header("host"), address) {
        return respond(
            stream,
            403,
            "text/plain",
            b"this server answers only to its own address",
        );
    }
    if request.method != "GET" {
        return respond(stream, 405, "text/plain", b"only GET");
    }
    match request.path.as_str() {
        "/" | "/index.html" => respond(
            stream,
            200,
            "text/html; charset=utf-8",
            PAGE_HTML.as_bytes(),
        ),
        // Browsers ask for it unprompted; an empty answer keeps their consoles quiet.
        "/favicon.ico" => respond(stream, 204, "image/x-icon", b""),
        "/live.js" => match LIVE_JS {
            Some(js) => respond(stream, 200, "text/javascript; charset=utf-8", js.as_bytes()),
            None => respond(
                stream,
                404,
                "text/plain",
                b"this visage was built without the page's viewer (web/viewer/build.sh)",
            ),
        },
        SOCKET_PATH => {
            let host = request.header("host").unwrap_or_default();
            match request.header("origin") {
                Some(origin) if origin != format!("http://{host}") => respond(
                    stream,
                    403,
                    "text/plain",
                    b"cross-origin WebSocket requests are refused",
                ),
                _ => watch(stream, shared),
            }
        }
        _ => respond(stream, 404, "text/plain", b"not found"),
    }
}

/// The WebSocket of one browser: the handshake, then its slot's messages until it goes.
fn watch(stream: TcpStream, shared: &Mutex<Shared>) {
    let Ok(mut socket) = tungstenite::accept(stream) else {
        return;
    };
    let slot: Slot = Arc::new((Mutex::new(Outbox::default()), Condvar::new()));
    {
        let mut shared = lock(shared);
        lock_outbox(&slot).topology = shared.topology.clone();
        shared.browsers.push(Arc::clone(&slot));
    }
    let result = send_frames(&mut socket, &slot);
    lock_outbox(&slot).closed = true;
    if result.is_ok() {
        let _ = socket.close(None);
        let _ = socket.flush();
    }
}

/// Writes the slot's messages as they come; ends when the browser or the page goes.
fn send_frames(socket: &mut WebSocket<TcpStream>, slot: &Slot) -> tungstenite::Result<()> {
    loop {
        let (topology, frame) = {
            let mut outbox = lock_outbox(slot);
            while outbox.topology.is_none() && outbox.frame.is_none() && !outbox.closed {
                outbox = slot.1.wait(outbox).unwrap_or_else(|e| e.into_inner());
            }
            if outbox.closed {
                return Ok(());
            }
            // The topology is always set before a frame of a new mesh (under the same lock):
            // sent first, it reaches the browser before the vertices it describes.
            (outbox.topology.take(), outbox.frame.take())
        };
        if let Some(t) = topology {
            socket.send(Message::text(t.as_str()))?;
        }
        if let Some((bytes, captured_at)) = frame {
            let mut bytes = bytes.as_ref().clone();
            let latency = captured_at.elapsed().as_secs_f64() as f32 * 1e3;
            bytes[8..12].copy_from_slice(&latency.to_le_bytes());
            socket.send(Message::binary(bytes))?;
        }
    }
}

/// Whether a request's `Host` names this server: the address it listens on, or `localhost`
/// with its port when that address is a loopback one.
fn host_allowed(host: Option<&str>, address: SocketAddr) -> bool {
    let Some(host) = host else {
        return false;
    };
    let port = address.port();
    host == address.to_string()
        || (address.ip().is_loopback() && host == format!("localhost:{port}"))
}

/// The request head, read without taking it off the socket (the WebSocket handshake reads it
/// again).
fn peek_head(stream: &TcpStream) -> Option<String> {
    let mut buffer = vec![0u8; MAX_HEAD];
    let started = Instant::now();
    loop {
        let n = stream.peek(&mut buffer).ok()?;
        if n == 0 {
            return None;
        }
        if let Some(end) = buffer[..n].windows(4).position(|w| w == b"\r\n\r\n") {
            return String::from_utf8(buffer[..end].to_vec()).ok();
        }
        if n == MAX_HEAD || started.elapsed() > IO_TIMEOUT {
            return None;
        }
        std::thread::sleep(Duration::from_millis(5));
    }
}

/// A request's line and headers (names lower-cased).
struct Request {
    method: String,
    path: String,
    headers: Vec<(String, String)>,
}

impl Request {
    fn parse(head: &str) -> Option<Request> {
        let mut lines = head.split("\r\n");
        let mut first = lines.next()?.split(' ');
        let method = first.next()?.to_owned();
        let target = first.next()?;
        let path = target.split('?').next()?.to_owned();
        let headers = lines
            .filter_map(|l| l.split_once(':'))
            .map(|(k, v)| (k.trim().to_ascii_lowercase(), v.trim().to_owned()))
            .collect();
        Some(Request {
            method,
            path,
            headers,
        })
    }

    fn header(&self, name: &str) -> Option<&str> {
        self.headers
            .iter()
            .find(|(k, _)| k == name)
            .map(|(_, v)| v.as_str())
    }
}

/// A whole response, then the connection closes.
fn respond(mut stream: TcpStream, status: u16, content_type: &str, body: &[u8]) {
    let reason = match status {
        200 => "OK",
        204 => "No Content",
        400 => "Bad Request",
        403 => "Forbidden",
        404 => "Not Found",
        _ => "Method Not Allowed",
    };
    let head = format!(
        "HTTP/1.1 {status} {reason}\r\nContent-Type: {content_type}\r\nContent-Length: {}\r\n\
         Cache-Control: no-store\r\nX-Content-Type-Options: nosniff\r\n\
         Content-Security-Policy: default-src 'self'; style-src 'self' 'unsafe-inline'\r\n\
         Connection: close\r\n\r\n",
        body.len()
    );
    let _ = stream.write_all(head.as_bytes());
    let _ = stream.write_all(body);
    let _ = stream.flush();
    // Read what is left of the request so the close is not a reset.
    let _ = stream.set_read_timeout(Some(Duration::from_millis(100)));
    let _ = stream.read(&mut [0u8; 1024]);
}

fn lock(shared: &Mutex<Shared>) -> std::sync::MutexGuard<'_, Shared> {
    shared.lock().unwrap_or_else(|e| e.into_inner())
}

fn lock_outbox(slot: &Slot) -> std::sync::MutexGuard<'_, Outbox> {
    slot.0.lock().unwrap_or_else(|e| e.into_inner())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ask(address: SocketAddr, request: &str) -> String {
        let mut s = TcpStream::connect(address).unwrap();
        s.write_all(request.as_bytes()).unwrap();
        let mut out = String::new();
        let _ = s.read_to_string(&mut out);
        out
    }

    #[test]
    fn it_serves_its_page_only_to_its_own_address_and_refuses_other_origins() {
        let page = LivePage::bind("127.0.0.1:0").unwrap();
        let a = page.address();
        let host = a.to_string();
        let ok = ask(a, &format!("GET / HTTP/1.1\r\nHost: {host}\r\n\r\n"));
        assert!(ok.starts_with("HTTP/1.1 200"), "{ok}");
        assert!(ok.contains("<canvas") || ok.contains("visage live"), "{ok}");
        let local = ask(
            a,
            &format!("GET / HTTP/1.1\r\nHost: localhost:{}\r\n\r\n", a.port()),
        );
        assert!(local.starts_with("HTTP/1.1 200"), "{local}");
        // Another name resolving here (DNS rebinding) gets nothing.
        let other = ask(
            a,
            &format!("GET / HTTP/1.1\r\nHost: evil.example:{}\r\n\r\n", a.port()),
        );
        assert!(other.starts_with("HTTP/1.1 403"), "{other}");
        // Nothing but its own files.
        let file = ask(
            a,
            &format!("GET /../Cargo.toml HTTP/1.1\r\nHost: {host}\r\n\r\n"),
        );
        assert!(file.starts_with("HTTP/1.1 404"), "{file}");
        let post = ask(a, &format!("POST / HTTP/1.1\r\nHost: {host}\r\n\r\n"));
        assert!(post.starts_with("HTTP/1.1 405"), "{post}");
        // A WebSocket asked for by a page of another origin.
        let upgrade = |origin: &str| {
            format!(
                "GET {SOCKET_PATH} HTTP/1.1\r\nHost: {host}\r\nUpgrade: websocket\r\n\
                 Connection: Upgrade\r\nSec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\n\
                 Sec-WebSocket-Version: 13\r\nOrigin: {origin}\r\n\r\n"
            )
        };
        let refused = ask(a, &upgrade("http://evil.example"));
        assert!(refused.starts_with("HTTP/1.1 403"), "{refused}");
        assert!(refused.contains("cross-origin"), "{refused}");
        let localhost = ask(a, &upgrade(&format!("http://localhost:{}", a.port())));
        assert!(localhost.starts_with("HTTP/1.1 403"), "{localhost}");
        // The page's own origin is switched to the WebSocket protocol.
        let mut s = TcpStream::connect(a).unwrap();
        s.write_all(upgrade(&format!("http://{host}")).as_bytes())
            .unwrap();
        let mut buf = [0u8; 256];
        let n = s.read(&mut buf).unwrap();
        let answer = String::from_utf8_lossy(&buf[..n]);
        assert!(answer.starts_with("HTTP/1.1 101"), "{answer}");
    }

    #[test]
    fn a_port_alone_is_bound_on_the_loopback_address() {
        let probe = TcpListener::bind("127.0.0.1:0").unwrap();
        let port = probe.local_addr().unwrap().port();
        drop(probe);
        let page = LivePage::bind(&port.to_string()).unwrap();
        assert!(page.address().ip().is_loopback());
        assert_eq!(page.url(), format!("http://127.0.0.1:{port}/"));
        assert!(LivePage::bind("no-such-host.invalid:80").is_err());
    }
}
