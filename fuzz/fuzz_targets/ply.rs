//! The PLY reader on arbitrary bytes: it may refuse the input, never panic or allocate beyond
//! the input's size; every index of a mesh it accepts must be in range.
#![no_main]
use libfuzzer_sys::fuzz_target;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    if let Ok(m) = mcrt::scene::ply::parse_ply(Path::new("fuzz.ply"), data) {
        let n = m.positions.len() as u32;
        assert!(m.indices.iter().flatten().all(|&i| i < n));
    }
});
