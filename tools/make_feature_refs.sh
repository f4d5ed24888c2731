#!/bin/sh
# Re-creates the Mitsuba 3 references of the XML feature scenes (tests/xml_features.rs).
# Needs Mitsuba 3 (see tools/mitsuba_ref.py). About a minute on two cores; `beckmann` uses
# scalar_rgb (40 s), which needs no LLVM.
set -e
cd "$(dirname "$0")/.."
for s in lights materials textures cameras orthographic shapes principled principled-textured \
    textured-params instances maps-mask spot envmap envmap-direct; do
    python3 tools/mitsuba_ref.py tests/data/mitsuba/features/$s.xml tests/data/refs/$s.exr 4096 --pass-spp 512
done
python3 tools/mitsuba_ref.py tests/data/mitsuba/features/beckmann.xml tests/data/refs/beckmann.exr 4096 --pass-spp 512 --variant scalar_rgb
# The glTF scene's Mitsuba twins (tests/gltf.rs); gltf/make_scene.py writes them.
python3 tools/mitsuba_ref.py tests/data/gltf/twin.xml tests/data/refs/gltf-twin.exr 4096 --pass-spp 512
python3 tools/mitsuba_ref.py tests/data/gltf/twin-principled.xml tests/data/refs/gltf-twin-principled.exr 4096 --pass-spp 512 --seed 100
