//! The TFLite model reader: `Network::from_tflite` (the flatbuffer reader `TfliteModel::parse`,
//! then the graph compiler), which `FaceDetector::from_bytes`, `LandmarkNetwork::from_bytes` and
//! `IrisNetwork::from_bytes` load the model files with. Any bytes give a compiled network or an
//! error, never a panic, hang or huge allocation. A network that compiles with a small input is
//! also run once: the compiler must have rejected every graph its kernels cannot execute.
#![no_main]

use libfuzzer_sys::fuzz_target;
use visage_nn::Network;

/// Largest input (values) of a compiled network that is run, to keep iterations fast.
const MAX_RUN_INPUT: usize = 1 << 12;

fuzz_target!(|data: &[u8]| {
    match Network::from_tflite(data, "fuzz.tflite") {
        Ok(mut net) => {
            if net.input_mut().len() <= MAX_RUN_INPUT {
                net.input_mut().fill(0.5);
                net.run();
                let mut k = 0;
                while let Some((_, values)) = net.output(k) {
                    std::hint::black_box(values);
                    k += 1;
                }
            }
        }
        Err(e) => drop(e.to_string()),
    }
});
