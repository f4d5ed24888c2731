//! Photon-map kd-tree: build and k-nearest queries (criterion). `cargo bench --bench photon_map`.

use criterion::{black_box, criterion_group, criterion_main, BenchmarkId, Criterion};
use glam::Vec3A;
use mcrt::photon::{Photon, PhotonMap};
use mcrt::sampler::Pcg32;
use mcrt::Color;
use std::collections::BinaryHeap;

/// Photons on the six faces of a unit cube (surface-like, as real photon maps are).
fn photons(n: usize) -> Vec<Photon> {
    let mut rng = Pcg32::new(7, 11);
    (0..n)
        .map(|_| {
            let (a, b) = (rng.next_1d(), rng.next_1d());
            let face = rng.next_u32() % 6;
            let s = if face.is_multiple_of(2) { 0.0 } else { 1.0 };
            let p = match face / 2 {
                0 => Vec3A::new(s, a, b),
                1 => Vec3A::new(a, s, b),
                _ => Vec3A::new(a, b, s),
            };
            Photon::new(p, Color::splat(1e-6), Vec3A::Z, 1, false)
        })
        .collect()
}

fn bench(c: &mut Criterion) {
    let mut g = c.benchmark_group("photon_map");
    g.sample_size(10);
    for n in [100_000usize, 1_000_000] {
        let ph = photons(n);
        g.bench_with_input(BenchmarkId::new("build", n), &ph, |b, ph| {
            b.iter(|| PhotonMap::build(black_box(ph.clone())))
        });
        let map = PhotonMap::build(ph);
        for k in [16usize, 64] {
            let mut rng = Pcg32::new(3, 5);
            let (mut heap, mut out) = (BinaryHeap::new(), Vec::new());
            g.bench_function(BenchmarkId::new(format!("knn{k}"), n), |b| {
                b.iter(|| {
                    let q = Vec3A::new(rng.next_1d(), rng.next_1d(), 0.0);
                    map.k_nearest(q, k, 0.01, &|_| true, &mut heap, &mut out);
                    black_box(out.len())
                })
            });
        }
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
