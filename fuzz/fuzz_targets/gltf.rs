//! The glTF importer on arbitrary bytes (JSON `.gltf` or binary `.glb`): it may refuse the
//! input, never panic; what it accepts must pass the scene limits and build into a scene.
#![no_main]
use libfuzzer_sys::fuzz_target;
use mcrt::scene::gltf::parse_gltf;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    let lenient = data.last().is_some_and(|b| b & 1 == 1);
    if let Ok(desc) = parse_gltf(Path::new("/nonexistent/fuzz.gltf"), data, lenient) {
        if desc.check_limits().is_ok() {
            let _ = mcrt::scene::Scene::build(desc);
        }
    }
});
