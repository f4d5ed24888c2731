//! The OBJ reader on arbitrary text: it may refuse the input, never panic; every index of a
//! mesh it accepts must be in range.
#![no_main]
use libfuzzer_sys::fuzz_target;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    if let Ok(text) = std::str::from_utf8(data) {
        if let Ok(m) = mcrt::scene::obj::parse_obj(Path::new("fuzz.obj"), text) {
            let n = m.positions.len() as u32;
            assert!(m.indices.iter().flatten().all(|&i| i < n));
        }
    }
});
