//! The serialized-mesh reader on arbitrary bytes (the first byte picks the shape index): it
//! may refuse the input, never panic or allocate beyond what the memory check allows; every
//! index of a mesh it accepts must be in range and every position finite.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Some((&index, bytes)) = data.split_first() else {
        return;
    };
    if let Ok(m) = mcrt::scene::serialized::parse_serialized(bytes, (index % 4) as u32) {
        let n = m.positions.len() as u32;
        assert!(m.indices.iter().flatten().all(|&i| i < n));
        assert!(m.positions.iter().all(|p| p.is_finite()));
    }
});
