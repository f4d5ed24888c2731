//! OpenEXR images as `compare` reads them (`image::decode_exr`, after the memory check on
//! the header's size): it may refuse the input, never panic or allocate beyond the memory
//! budget; an accepted image has as many pixels as its size says.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Ok(img) = mcrt::image::decode_exr(data) {
        assert_eq!(img.pixels.len() as u64, img.width as u64 * img.height as u64);
    }
});
