//! PNG and OpenEXR textures as `render` loads them (`texture::Bitmap::decode`, after the
//! memory check on the header's size): it may refuse the input, never panic or allocate
//! beyond the memory budget; an accepted bitmap has its claimed size and only finite,
//! non-negative texels (the rule of constant colours).
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let raw = data.len() % 2 == 0;
    if let Ok(b) = mcrt::texture::Bitmap::decode(data, raw) {
        assert_eq!(b.pixels().len() as u64, b.width as u64 * b.height as u64);
        assert!(b.pixels().all(|p| p.is_finite() && p.min_element() >= 0.0));
    }
});
