//! The native TOML scene loader on arbitrary text: it may refuse the input, never panic; what
//! it accepts must build into a scene.
#![no_main]
use libfuzzer_sys::fuzz_target;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    if let Ok(text) = std::str::from_utf8(data) {
        if let Ok(desc) = mcrt::scene::toml::parse_toml(Path::new("/nonexistent/fuzz.toml"), text) {
            let _ = mcrt::scene::Scene::build(desc);
        }
    }
});
