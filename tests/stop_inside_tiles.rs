//! A stop takes effect inside a tile (issue 27, class 5): the render asks between steps of a
//! few thousand samples, not only between tiles, and what it leaves is still a prefix of every
//! pixel's samples, so continuing gives the same bits as one uninterrupted render.

mod common;

use mcrt::film::Film;
use mcrt::scene::desc::FileSettings;
use std::sync::atomic::{AtomicUsize, Ordering};

#[test]
fn a_stop_inside_a_single_tile_leaves_prefixes_that_continue_bit_for_bit() {
    let (scene, fs) = common::load("scenes/cornell-box.toml");
    let spp = 64;
    // One 16 × 16 tile at 64 spp: 16 384 samples, several steps.
    let s = common::settings(
        &fs,
        FileSettings {
            width: Some(16),
            height: Some(16),
            spp: Some(spp),
            ..Default::default()
        },
    );
    let npix = 16 * 16;
    let until = |_| spp;
    // Told to stop after the first step.
    let asked = AtomicUsize::new(0);
    let stop = || asked.fetch_add(1, Ordering::SeqCst) >= 2;
    let mut film = Film::new(16, 16);
    let mut next = vec![0; npix];
    let integrator = mcrt::integrator::prepare(&scene, &s, &|| false).unwrap();
    let ranges = |film: &mut Film, next: &mut [u32], stop: &(dyn Fn() -> bool + Sync)| {
        mcrt::render::render_ranges(&*integrator, &scene, &s, film, next, &until, stop, &|_| {})
            .unwrap()
    };
    let st = ranges(&mut film, &mut next, &stop);
    assert!(st.interrupted, "the stop was not seen");
    let done: u64 = next.iter().map(|&n| n as u64).sum();
    assert!(
        done > 0 && done < (npix as u64) * spp as u64,
        "the tile should stop part way ({done} samples)"
    );
    assert_eq!(st.samples, done);
    // Continue to the end, and compare with one uninterrupted render.
    let st2 = ranges(&mut film, &mut next, &|| false);
    assert!(!st2.interrupted);
    assert!(next.iter().all(|&n| n == spp));
    let mut whole = Film::new(16, 16);
    let mut next_whole = vec![0; npix];
    ranges(&mut whole, &mut next_whole, &|| false);
    assert_eq!(film.sum, whole.sum);
    assert_eq!(film.sum_sq, whole.sum_sq);
    assert_eq!(film.count, whole.count);
}
