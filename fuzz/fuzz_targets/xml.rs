//! The Mitsuba XML importer on arbitrary text: it may refuse the input, never panic; what it
//! accepts must build into a scene.
#![no_main]
use libfuzzer_sys::fuzz_target;
use mcrt::scene::xml::{parse_xml, XmlOptions};
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    if let Ok(text) = std::str::from_utf8(data) {
        let opts = XmlOptions {
            defines: vec![("spp".into(), "4".into())],
            lenient: data.first().is_some_and(|b| b & 1 == 1),
        };
        if let Ok(desc) = parse_xml(Path::new("/nonexistent/fuzz.xml"), text, &opts) {
            let _ = mcrt::scene::Scene::build(desc);
        }
    }
});
