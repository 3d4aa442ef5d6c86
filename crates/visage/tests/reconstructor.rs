//! The facade on a real clip: the causal single-thread API and the threaded whole-input run
//! give the same meshes; clip mode hands every mesh over after the clip solve; bad options are
//! refused before any work, naming what is wrong.

use visage::{
    Camera, DepthSource, Error, FrameSink, Input, Intrinsics, LandmarksFrame, MeshFrame, MeshKind,
    ModelSource, Reconstructor, TemporalMode,
};

fn clip() -> std::path::PathBuf {
    visage_testdata::require(visage_testdata::shared_dir().join("data/video/lp_d18.mp4"))
}

fn builder() -> visage::Builder {
    Reconstructor::builder().models_dir(visage_testdata::models_dir())
}

/// Records what a run hands over, in order.
#[derive(Default)]
struct Collect {
    events: Vec<&'static str>,
    meshes: Vec<(usize, Vec<[f64; 3]>)>,
}

impl FrameSink for Collect {
    fn landmarks(&mut self, record: &LandmarksFrame) -> Result<(), Error> {
        let fused = record.faces[0].fused_landmarks.as_ref();
        assert_eq!(
            fused.map(Vec::len),
            Some(468),
            "every meshed frame's fused landmarks"
        );
        self.events.push("landmarks");
        Ok(())
    }

    fn frame_done(&mut self, _: &visage::FrameMetrics) {
        self.events.push("done");
    }
    fn mesh(&mut self, frame: &MeshFrame<'_>) -> Result<(), Error> {
        assert!(frame
            .triangles
            .iter()
            .flatten()
            .all(|&i| (i as usize) < frame.surfaces.fused.len()));
        self.events.push("mesh");
        self.meshes
            .push((frame.index, frame.surfaces.fused.clone()));
        Ok(())
    }
}

const FRAMES: usize = 10;

#[test]
#[cfg_attr(
    not(all(shared_data, model_files, ffmpeg)),
    ignore = "needs ../shared, the model files (scripts/setup.sh) and FFmpeg"
)]
fn process_and_run_give_the_same_meshes() {
    let input = Input::open(&clip()).unwrap().max_frames(FRAMES).unwrap();
    let mut single = builder().build_for(&input).unwrap();
    let mut by_process = Vec::new();
    for frame in input {
        let r = single.process(&frame.unwrap()).unwrap();
        let mesh = r.mesh().expect("every frame of this clip has a face");
        assert_eq!(r.surfaces().unwrap().fused, mesh.vertices);
        by_process.push((r.index(), mesh.vertices.clone()));
    }
    assert_eq!(single.frames().len(), FRAMES);

    // `process` answers each frame at once: the same as a run without latency.
    let input = Input::open(&clip()).unwrap().max_frames(FRAMES).unwrap();
    let mut sink = Collect::default();
    let outcome = builder()
        .latency(0)
        .build_for(&input)
        .unwrap()
        .run(input, &mut sink);
    assert!(outcome.error.is_none());
    assert_eq!(outcome.summary.solved, FRAMES);
    assert_eq!(sink.meshes, by_process, "threads must not change a result");
    assert_eq!(outcome.mesh.vertices, 1833);
    let q = outcome.summary.quality;
    assert!(q.vertex_jitter_mm.fused.unwrap() < q.vertex_jitter_mm.raw.unwrap());
}

#[test]
#[cfg_attr(
    not(all(shared_data, model_files, ffmpeg)),
    ignore = "needs ../shared, the model files (scripts/setup.sh) and FFmpeg"
)]
fn clip_mode_hands_the_meshes_over_after_the_clip_solve() {
    let input = Input::open(&clip()).unwrap().max_frames(FRAMES).unwrap();
    let streaming = {
        let mut sink = Collect::default();
        let r = builder().build_for(&input).unwrap();
        let input = Input::open(&clip()).unwrap().max_frames(FRAMES).unwrap();
        r.run(input, &mut sink);
        sink.meshes
    };
    let mut sink = Collect::default();
    let outcome = builder()
        .mode(TemporalMode::Clip)
        .build_for(&input)
        .unwrap()
        .run(input, &mut sink);
    assert!(outcome.error.is_none());
    let first_mesh = sink.events.iter().position(|e| *e == "mesh").unwrap();
    assert_eq!(
        sink.events[..first_mesh],
        ["done"; FRAMES],
        "all frames are fused before the clip solve"
    );
    // Each landmarks record waits for its mesh (its fused landmarks), in input order.
    assert_eq!(
        sink.events[first_mesh..],
        ["mesh", "landmarks"].repeat(FRAMES)
    );
    let indices: Vec<usize> = sink.meshes.iter().map(|m| m.0).collect();
    assert_eq!(indices, (0..FRAMES).collect::<Vec<_>>());
    assert!(outcome.frames.iter().all(|f| f.relative_residual < 1e-6));
    // Frame 0's streaming solution saw none of the later frames; its clip solution does.
    assert_ne!(sink.meshes[0].1, streaming[0].1);
}

#[test]
fn bad_options_are_refused_before_any_work() {
    let tmp = tempfile::tempdir().unwrap();
    let missing = tmp.path().join("nope.mp4");
    let e = Input::open(&missing).err().unwrap();
    assert!(e.to_string().contains("nope.mp4"), "{e}");

    image::RgbImage::new(64, 48)
        .save(tmp.path().join("a.png"))
        .unwrap();
    let input = Input::open(tmp.path()).unwrap();
    assert_eq!(
        (input.size(), input.frames_to_process()),
        ((64, 48), Some(1))
    );
    let e = Input::open(tmp.path()).unwrap().every(0).err().unwrap();
    assert!(e.to_string().contains("--every 0"), "{e}");

    // Refused before the models are looked for.
    let no_models = || Reconstructor::builder().models_dir(tmp.path().join("no-models"));
    let other = Intrinsics::from_fov(640, 480, 60.0).unwrap();
    let e = no_models()
        .intrinsics(other)
        .build_for(&input)
        .err()
        .unwrap();
    assert!(matches!(e, Error::Camera(_)), "{e}");
    let e = no_models()
        .camera(Camera::FovDeg(200.0))
        .build_for(&input)
        .err()
        .unwrap();
    assert!(e.to_string().contains("--fov-deg 200"), "{e}");
    let e = no_models().lambda(-1.0).build_for(&input).err().unwrap();
    assert!(e.to_string().contains("lambda"), "{e}");
    let e = no_models().latency(1000).build_for(&input).err().unwrap();
    assert!(e.to_string().contains("--latency 1000"), "{e}");
    let e = no_models()
        .landmark_smoothing(Some(-3.0))
        .build_for(&input)
        .err()
        .unwrap();
    assert!(e.to_string().contains("--smoothing -3"), "{e}");
    for (mesh, depth) in [
        (MeshKind::Model, DepthSource::Face),
        (MeshKind::Face, DepthSource::Model),
    ] {
        let e = no_models()
            .mesh(mesh)
            .depth(depth)
            .model(ModelSource::None)
            .build_for(&input)
            .err()
            .unwrap();
        assert!(e.to_string().contains("face model fit"), "{e}");
    }
    // Then the missing models are named.
    let e = no_models().build_for(&input).err().unwrap();
    assert!(e.to_string().contains("no-models"), "{e}");
}
