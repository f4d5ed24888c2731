//! Sums files and checkpoints as `merge` and `--resume` read them (`parts::decode_sums`,
//! `checkpoint::decode_checkpoint`: memory check on the header's size, checksum, counts): it
//! may refuse the input, never panic or allocate beyond the memory budget. An accepted file
//! has a film of its metadata's size whose counts stay within the samples it claims.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Ok(p) = mcrt::parts::decode_sums(data) {
        assert_eq!((p.film.width, p.film.height), p.meta.film_size());
        assert!(p.film.count.iter().all(|&c| c <= p.meta.count));
    }
    if let Ok(c) = mcrt::checkpoint::decode_checkpoint(data) {
        assert_eq!((c.film.width, c.film.height), c.meta.film_size());
        assert!(c.next.iter().zip(&c.film.count).all(|(n, k)| k <= n));
        assert!(c.next.iter().all(|&n| n <= c.meta.spp));
    }
});
