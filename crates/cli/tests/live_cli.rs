//! `visage live` as a VTuber setup runs it: a clip played at its own pace (as a camera delivers
//! frames) streamed by the VMC protocol to a UDP receiver, whose datagrams are decoded here as
//! OSC; and sources that cannot be opened.

mod common;

use std::net::UdpSocket;
use std::time::Duration;

use common::{s, visage};
use visage::ARKIT_BLENDSHAPES;

/// One OSC argument, as decoded.
#[derive(Debug, PartialEq)]
enum Arg {
    Int(i32),
    Float(f32),
    Str(String),
}

/// One decoded OSC message: its address and arguments.
type Message = (String, Vec<Arg>);

/// Reads an OSC string at `*at` (NUL-terminated, padded to 4).
fn read_str(bytes: &[u8], at: &mut usize) -> String {
    let end = *at + bytes[*at..].iter().position(|&b| b == 0).unwrap();
    let s = String::from_utf8(bytes[*at..end].to_vec()).unwrap();
    *at = (end + 4) & !3;
    s
}

/// The messages of one OSC packet (a message or a bundle of them).
fn decode(bytes: &[u8], out: &mut Vec<(String, Vec<Arg>)>) {
    let mut at = 0;
    if bytes.starts_with(b"#bundle\0") {
        at = 16;
        while at < bytes.len() {
            let n = i32::from_be_bytes(bytes[at..at + 4].try_into().unwrap()) as usize;
            decode(&bytes[at + 4..at + 4 + n], out);
            at += 4 + n;
        }
        return;
    }
    let address = read_str(bytes, &mut at);
    let tags = read_str(bytes, &mut at);
    assert!(tags.starts_with(','), "{tags}");
    let mut args = Vec::new();
    for t in tags[1..].chars() {
        let word = |at: &mut usize| {
            let w: [u8; 4] = bytes[*at..*at + 4].try_into().unwrap();
            *at += 4;
            w
        };
        args.push(match t {
            'i' => Arg::Int(i32::from_be_bytes(word(&mut at))),
            'f' => Arg::Float(f32::from_be_bytes(word(&mut at))),
            's' => Arg::Str(read_str(bytes, &mut at)),
            other => panic!("type tag {other}"),
        });
    }
    assert_eq!(at, bytes.len(), "{address}: trailing bytes");
    out.push((address, args));
}

/// A UDP receiver on a free local port: its address, and the thread that decodes what it
/// receives as OSC until nothing has come for 5 s.
fn vmc_receiver() -> (String, std::thread::JoinHandle<Vec<Message>>) {
    let receiver = UdpSocket::bind("127.0.0.1:0").unwrap();
    receiver
        .set_read_timeout(Some(Duration::from_millis(200)))
        .unwrap();
    let target = receiver.local_addr().unwrap().to_string();
    let collect = std::thread::spawn(move || {
        let (mut messages, mut buffer, mut idle) = (Vec::new(), [0u8; 65536], 0);
        while idle < 25 {
            match receiver.recv(&mut buffer) {
                Ok(n) => {
                    idle = 0;
                    decode(&buffer[..n], &mut messages);
                }
                Err(_) => idle += 1,
            }
        }
        messages
    });
    (target, collect)
}

/// A clip played at its pace to a VMC receiver: every processed frame with a face arrives as
/// OK, T, the 52 ARKit weights by name in [0, 1], then Apply; times increase; the closing line
/// counts frames in, processed and dropped, and gives the latency.
#[test]
#[cfg_attr(
    not(all(shared_data, model_files, ffmpeg)),
    ignore = "needs ../shared, the model files (scripts/setup.sh) and FFmpeg"
)]
fn a_clip_played_live_reaches_a_vmc_receiver_frame_by_frame() {
    let (models, clip) = common::inputs();
    let (target, collect) = vmc_receiver();
    let o = visage(&[
        "live",
        s(&clip),
        "--realtime",
        "--vmc",
        &target,
        "--max-frames",
        "30",
        "--models",
        s(&models),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    let messages = collect.join().unwrap();

    let processed: usize = err
        .split(" processed")
        .next()
        .and_then(|s| s.rsplit(", ").next())
        .and_then(|n| n.parse().ok())
        .unwrap_or_else(|| panic!("{err}"));
    assert_eq!(processed, 30, "{err}");
    assert!(
        err.contains("dropped") && err.contains("latency p50"),
        "{err}"
    );
    let frames: Vec<&[(String, Vec<Arg>)]> = messages
        .split_inclusive(|(a, _)| a == "/VMC/Ext/Blend/Apply")
        .filter(|f| f.last().is_some_and(|(a, _)| a == "/VMC/Ext/Blend/Apply"))
        .collect();
    assert_eq!(
        frames.len(),
        30,
        "one applied frame per processed frame (the clip has a face)"
    );
    let mut last_t = -1.0;
    for frame in frames {
        assert_eq!(frame[0], ("/VMC/Ext/OK".into(), vec![Arg::Int(1)]));
        let Arg::Float(t) = frame[1].1[0] else {
            panic!("{:?}", frame[1])
        };
        assert!(frame[1].0 == "/VMC/Ext/T" && t > last_t, "{:?}", frame[1]);
        last_t = t;
        let values = &frame[2..frame.len() - 1];
        assert_eq!(values.len(), 52);
        for ((address, args), name) in values.iter().zip(ARKIT_BLENDSHAPES) {
            assert_eq!(address, "/VMC/Ext/Blend/Val");
            assert_eq!(args[0], Arg::Str(name.to_string()));
            let Arg::Float(w) = args[1] else {
                panic!("{args:?}")
            };
            assert!((0.0..=1.0).contains(&w), "{name} = {w}");
        }
    }
    // Played at its pace (30 fps) the 30 frames take about a second.
    assert!(last_t > 0.8, "the last frame at {last_t} s");
}

/// A source FFmpeg cannot open: exit 2, naming it and FFmpeg's reason.
#[test]
#[cfg_attr(not(ffmpeg), ignore = "needs FFmpeg")]
fn a_source_that_cannot_be_opened_is_exit_2_naming_it() {
    let o = visage(&[
        "live",
        "/nonexistent/camera.mp4",
        "--vmc",
        "127.0.0.1:39539",
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("/nonexistent/camera.mp4") && err.contains("No such file"),
        "{err}"
    );
}

/// Real clients from PyPI while the sample clip plays at its pace: `pylivelinkface` decodes
/// the Live Link packets and `python-osc` the VMC bundles; both carry, frame by frame, the
/// weights of the same frames' rows in `blendshapes.csv` of the session's own recording.
#[test]
#[cfg_attr(
    not(all(shared_data, model_files, ffmpeg)),
    ignore = "needs ../shared, the model files (scripts/setup.sh) and FFmpeg"
)]
fn real_clients_decode_the_streams_as_the_recorded_weights() {
    let target_dir = std::env::var_os("CARGO_TARGET_DIR")
        .map(std::path::PathBuf::from)
        .unwrap_or_else(|| visage_testdata::workspace_root().join("target"));
    let python = target_dir.join("live-venv/bin/python");
    if !python.is_file() {
        assert!(
            std::env::var("CI").as_deref() != Ok("true"),
            "{} is missing: run scripts/setup.sh",
            python.display()
        );
        eprintln!(
            "skipped: no {} (scripts/setup.sh makes it)",
            python.display()
        );
        return;
    }
    let (models, clip) = common::inputs();
    let tmp = tempfile::tempdir().unwrap();
    let decoded = tmp.path().join("decoded.json");
    let take = tmp.path().join("take");
    // Two sockets, one per stream; each datagram decoded by its client package.
    let client = "import socket, sys, json, select\n\
        from pylivelinkface import PyLiveLinkFace, FaceBlendShape\n\
        from pythonosc.osc_packet import OscPacket\n\
        llf = socket.socket(socket.AF_INET, socket.SOCK_DGRAM); llf.bind(('127.0.0.1', 0))\n\
        vmc = socket.socket(socket.AF_INET, socket.SOCK_DGRAM); vmc.bind(('127.0.0.1', 0))\n\
        print(llf.getsockname()[1], vmc.getsockname()[1], flush=True)\n\
        packets, frames, current = [], [], []\n\
        while True:\n\
        \x20   ready, _, _ = select.select([llf, vmc], [], [], 5)\n\
        \x20   if not ready: break\n\
        \x20   for s in ready:\n\
        \x20       data, _ = s.recvfrom(65536)\n\
        \x20       if s is llf:\n\
        \x20           ok, face = PyLiveLinkFace.decode(data)\n\
        \x20           packets.append({'ok': ok, 'name': face.name, 'uuid': face.uuid, 'fps': face.fps,\n\
        \x20                           'shapes': {b.name: face.get_blendshape(b) for b in FaceBlendShape}})\n\
        \x20           continue\n\
        \x20       for m in OscPacket(data).messages:\n\
        \x20           m = m.message\n\
        \x20           if m.address == '/VMC/Ext/Blend/Val': current.append([m.params[0], m.params[1]])\n\
        \x20           elif m.address == '/VMC/Ext/Blend/Apply': frames.append(current); current = []\n\
        json.dump({'packets': packets, 'vmc': frames}, open(sys.argv[1], 'w'))\n";
    let mut receiver = std::process::Command::new(&python)
        .args(["-c", client])
        .arg(&decoded)
        .stdout(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let mut ports = String::new();
    std::io::BufRead::read_line(
        &mut std::io::BufReader::new(receiver.stdout.take().unwrap()),
        &mut ports,
    )
    .unwrap();
    let ports: Vec<&str> = ports.split_whitespace().collect();
    let o = visage(&[
        "live",
        s(&clip),
        "--realtime",
        "--max-frames",
        "20",
        "--vmc",
        &format!("127.0.0.1:{}", ports[1]),
        "--live-link",
        &format!("127.0.0.1:{}", ports[0]),
        "--subject",
        "Actor",
        "--out",
        s(&take),
        "--models",
        s(&models),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert!(receiver.wait().unwrap().success());
    let decoded = common::json(&decoded);
    let packets = decoded["packets"].as_array().unwrap();
    let vmc = decoded["vmc"].as_array().unwrap();
    // The recording's rows: every processed frame, in order.
    let csv = std::fs::read_to_string(take.join("blendshapes.csv")).unwrap();
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    assert_eq!(rows.len(), 20, "{err}");
    assert_eq!(packets.len(), 20, "one packet per frame with a face");
    assert_eq!(vmc.len(), 20, "one applied frame per frame with a face");
    for ((packet, weights), row) in packets.iter().zip(vmc).zip(&rows) {
        assert_eq!(packet["ok"], true);
        assert_eq!(packet["name"], "Actor");
        assert_eq!(packet["fps"], 60);
        // pylivelinkface keeps the length's low byte, '$' (36), before a 36-character id.
        assert_eq!(
            packet["uuid"],
            format!("${}", visage::live::DEFAULT_DEVICE_ID)
        );
        let weights = weights.as_array().unwrap();
        assert_eq!(weights.len(), 52);
        for (pair, name) in weights.iter().zip(ARKIT_BLENDSHAPES) {
            assert_eq!(pair[0], name);
            let w = pair[1].as_f64().unwrap();
            let mut column = name.to_string();
            column[..1].make_ascii_uppercase();
            let recorded: f64 = row[header.iter().position(|h| *h == column).unwrap()]
                .parse()
                .unwrap();
            assert!(
                (w - recorded).abs() < 1e-6,
                "{name}: VMC {w}, CSV {recorded}"
            );
            let llf = packet["shapes"][&column].as_f64().unwrap();
            assert!(
                (llf - recorded).abs() < 1e-6,
                "{name}: Live Link {llf}, CSV {recorded}"
            );
        }
    }
}

/// A live session recorded with `--out`: the folder `visage run` writes, every processed
/// frame in it with its latency, and `visage export` makes a glb of it; a second session into
/// the same folder is refused, as a second run is.
#[test]
#[cfg_attr(
    not(all(shared_data, model_files, ffmpeg)),
    ignore = "needs ../shared, the model files (scripts/setup.sh) and FFmpeg"
)]
fn a_recorded_session_is_a_run_folder_that_exports() {
    let (models, clip) = common::inputs();
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("take");
    let args = [
        "live",
        s(&clip),
        "--realtime",
        "--out",
        s(&out),
        "--max-frames",
        "25",
        "--models",
        s(&models),
    ];
    let o = visage(&args);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert!(err.contains("recorded into"), "{err}");
    let m = common::json(&out.join("metrics.json"));
    assert_eq!(m["status"], "complete");
    let frames = m["frames"].as_array().unwrap();
    assert_eq!(frames.len(), 25);
    assert!(frames
        .iter()
        .all(|f| f["latency_ms"].as_f64().is_some_and(|ms| ms > 0.0)));
    let cache = visage_mesh::io::read_pc2(&out.join("sequence.pc2")).unwrap();
    assert_eq!(cache.samples(), 25);
    let csv = std::fs::read_to_string(out.join("blendshapes.csv")).unwrap();
    assert_eq!(csv.lines().count(), 26);
    common::run_ok(&["export", s(&out), "--glb", "--quiet"]);
    assert!(out.join("sequence.glb").is_file());

    let o = visage(&args);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("not empty"), "{err}");
}

/// The closing line's count of processed frames.
fn processed(err: &str) -> usize {
    err.split(" processed")
        .next()
        .and_then(|s| s.rsplit(", ").next())
        .and_then(|n| n.parse().ok())
        .unwrap_or_else(|| panic!("{err}"))
}

/// A free UDP port on the loopback address.
fn free_udp_port() -> u16 {
    UdpSocket::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port()
}

/// FFmpeg serves the sample clip as MPEG-TS over UDP at its own pace; `visage live udp://…`
/// reads it as it comes, to its end, and ends when the stream goes quiet, cleanly. (How many
/// frames are processed depends on the machine — the newest frame wins, and a debug build on a
/// busy machine keeps up with fewer than 30 a second —, so the test asks that the frames arrive
/// and that the last one sent is the last one processed.)
#[test]
#[cfg_attr(
    not(all(shared_data, model_files, ffmpeg)),
    ignore = "needs ../shared, the model files (scripts/setup.sh) and FFmpeg"
)]
fn a_network_stream_is_processed_to_its_end() {
    let (models, clip) = common::inputs();
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("take");
    let url = format!("udp://127.0.0.1:{}", free_udp_port());
    let live = std::process::Command::new(env!("CARGO_BIN_EXE_visage"))
        .args(["live", &url, "--idle-end", "2", "--out", s(&out)])
        .args(["--models", s(&models)])
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    // FFmpeg in `visage live` listens within a moment; the sender starts after it.
    std::thread::sleep(Duration::from_secs(2));
    let sent = std::process::Command::new("ffmpeg")
        .args([
            "-v",
            "error",
            "-re",
            "-i",
            s(&clip),
            "-c",
            "copy",
            "-f",
            "mpegts",
        ])
        .arg(format!("{url}?pkt_size=1316"))
        .status()
        .unwrap();
    assert!(sent.success());
    let o = live.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert!(
        err.contains("no frame for 2 s: the stream is over"),
        "{err}"
    );
    // 216 frames sent; the decoder may give up a few at the stream's start (it joins it
    // between key frames' references).
    let frames_in: usize = err
        .split(" frames in")
        .next()
        .and_then(|s| s.rsplit(' ').next())
        .and_then(|n| n.parse().ok())
        .unwrap_or_else(|| panic!("{err}"));
    assert!(frames_in >= 200, "{frames_in} frames arrived: {err}");
    assert!(processed(&err) > 0, "{err}");
    let m = common::json(&out.join("metrics.json"));
    let last = m["frames"].as_array().unwrap().last().unwrap()["index"].clone();
    assert_eq!(
        last,
        frames_in - 1,
        "the last frame that came was processed"
    );
}

/// `visage live --listen` serves its page: in headless Chromium the face's canvas changes from
/// one second to the next and the page reports the frame rate and latency; a page of another
/// origin asking for the socket is refused. The clip is streamed through standard input in a
/// loop, so the page is checked while frames still come; Ctrl-C ends the session.
#[test]
#[cfg_attr(
    not(all(shared_data, model_files, ffmpeg, web_tools)),
    ignore = "needs ../shared, the model files, FFmpeg and web/viewer built (scripts/setup.sh)"
)]
fn the_live_page_shows_the_face_moving_and_refuses_other_origins() {
    use std::io::BufRead;
    use std::process::{Command, Stdio};
    let (models, clip) = common::inputs();
    let mut feed = Command::new("ffmpeg")
        .args(["-v", "error", "-re", "-stream_loop", "-1", "-i", s(&clip)])
        .args(["-an", "-c:v", "mjpeg", "-q:v", "3", "-f", "nut", "pipe:1"])
        .stdout(Stdio::piped())
        // It says "Broken pipe" when the session ends first.
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let mut live = Command::new(env!("CARGO_BIN_EXE_visage"))
        .args([
            "live",
            "-",
            "--listen",
            "127.0.0.1:0",
            "--models",
            s(&models),
        ])
        .stdin(feed.stdout.take().unwrap())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut stderr = std::io::BufReader::new(live.stderr.take().unwrap());
    let mut line = String::new();
    let url = loop {
        line.clear();
        assert!(stderr.read_line(&mut line).unwrap() > 0, "no page address");
        if let Some(url) = line.trim().strip_prefix("the live page: ") {
            break url.to_owned();
        }
    };
    let port = url.trim_end_matches('/').rsplit(':').next().unwrap();
    let other = format!("http://localhost:{port}/");
    let artefacts = visage_testdata::workspace_root().join("target/test-artifacts");
    std::fs::create_dir_all(&artefacts).unwrap();
    let shot = artefacts.join("live-page.png");
    let check = Command::new("node")
        .arg(visage_testdata::web_dir().join("test/check_live.mjs"))
        .args([&url, &other, s(&shot)])
        .output()
        .unwrap();
    let _ = Command::new("kill")
        .args(["-INT", &live.id().to_string()])
        .status();
    let mut rest = String::new();
    let _ = std::io::Read::read_to_string(&mut stderr, &mut rest);
    let status = live.wait().unwrap();
    let _ = feed.kill();
    let _ = feed.wait();
    let report = String::from_utf8_lossy(&check.stdout);
    assert!(
        check.status.success(),
        "{report}{}",
        String::from_utf8_lossy(&check.stderr)
    );
    let json: serde_json::Value = serde_json::from_str(report.trim()).unwrap();
    assert_eq!(json["crossOrigin"], "refused", "{json}");
    assert!(json["fps"].as_f64().unwrap() > 0.0, "{json}");
    assert!(json["difference"].as_f64().unwrap() > 0.2, "{json}");
    assert!(status.success(), "{rest}");
    assert!(rest.contains("sent the live page at"), "{rest}");
}

/// `--vmc-bones`: before each frame's weights, the `Head`, `LeftEye` and `RightEye` bones as
/// unit quaternions; the sample's speaker looks down at the camera's lens (the fit reads a head
/// pitch of about 11°), which Unity's frame makes a positive rotation about x.
#[test]
#[cfg_attr(
    not(all(shared_data, model_files, ffmpeg)),
    ignore = "needs ../shared, the model files (scripts/setup.sh) and FFmpeg"
)]
fn vmc_bones_carry_the_heads_rotation_in_unitys_frame() {
    let (models, clip) = common::inputs();
    let (target, collect) = vmc_receiver();
    let o = visage(&[
        "live",
        s(&clip),
        "--realtime",
        "--vmc",
        &target,
        "--vmc-bones",
        "--max-frames",
        "20",
        "--models",
        s(&models),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let messages = collect.join().unwrap();
    let bones: Vec<&(String, Vec<Arg>)> = messages
        .iter()
        .filter(|(a, _)| a == "/VMC/Ext/Bone/Pos")
        .collect();
    assert_eq!(bones.len(), 3 * 20, "three bones a frame");
    let mut head_x = Vec::new();
    for (i, (_, args)) in bones.iter().enumerate() {
        let Arg::Str(name) = &args[0] else {
            panic!("{args:?}")
        };
        assert_eq!(name, ["Head", "LeftEye", "RightEye"][i % 3]);
        let q: Vec<f32> = args[4..8]
            .iter()
            .map(|a| match a {
                Arg::Float(v) => *v,
                other => panic!("{other:?}"),
            })
            .collect();
        let norm = q.iter().map(|v| v * v).sum::<f32>().sqrt();
        assert!((norm - 1.0).abs() < 1e-4, "{q:?}");
        if name == "Head" {
            head_x.push(q[0] * q[3].signum());
        }
    }
    head_x.sort_by(f32::total_cmp);
    let median = head_x[head_x.len() / 2];
    // sin(11° / 2) ≈ 0.096.
    assert!((0.03..0.2).contains(&median), "{head_x:?}");
}

/// `--latency 1`: each frame waits for the next one (the smoother's look-ahead), so at the
/// clip's 30 frames a second its latency holds a frame interval; every frame still comes out,
/// the last one when the source ends.
#[test]
#[cfg_attr(
    not(all(shared_data, model_files, ffmpeg)),
    ignore = "needs ../shared, the model files (scripts/setup.sh) and FFmpeg"
)]
fn a_frame_of_look_ahead_holds_each_frame_for_the_next() {
    let (models, clip) = common::inputs();
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("take");
    let o = visage(&[
        "live",
        s(&clip),
        "--realtime",
        "--latency",
        "1",
        "--max-frames",
        "15",
        "--out",
        s(&out),
        "--models",
        s(&models),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert_eq!(processed(&err), 15, "{err}");
    let m = common::json(&out.join("metrics.json"));
    assert_eq!(m["parameters"]["latency_frames"], 1, "{}", m["parameters"]);
    let mut ms: Vec<f64> = m["frames"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| f["latency_ms"].as_f64().unwrap())
        .collect();
    assert_eq!(ms.len(), 15);
    ms.sort_by(f64::total_cmp);
    // The next frame comes 33 ms after this one.
    assert!(ms[7] > 25.0, "{ms:?}");
}
