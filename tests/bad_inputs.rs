//! The corpus of bad inputs (tests/bad-inputs/): scene files in mcrt's TOML format, in
//! Mitsuba XML and in glTF, and OBJ and PLY meshes, each wrong in one way. Every one must make
//! `mcrt render` exit with status 2 and a message that names the file and says what is wrong
//! (the fragment after `expect:` in the file's first lines; a glTF file's `asset.generator`),
//! without a panic and without writing an output file. Meshes are rendered through a small
//! scene that loads them (TOML for OBJ, Mitsuba XML for PLY and serialized meshes), Radiance
//! HDR images through an XML scene's `envmap`.

mod common;

use common::cli::*;
use std::path::{Path, PathBuf};

fn corpus() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/bad-inputs")
}

/// The text after `expect:` in the first lines of a file.
fn expectation(path: &Path) -> String {
    let bytes = std::fs::read(path).unwrap();
    let text = String::from_utf8_lossy(&bytes[..bytes.len().min(400)]).into_owned();
    let at = text
        .find("expect:")
        .unwrap_or_else(|| panic!("{} has no expect: line", path.display()));
    let rest = &text[at + "expect:".len()..];
    let end = rest.find(['\n', '\r']).unwrap_or(rest.len());
    rest[..end]
        .trim()
        .trim_end_matches("-->")
        .trim()
        // A glTF file's expectation is a JSON string: `"expect: …",`.
        .trim_end_matches(',')
        .trim_end_matches('"')
        .to_string()
}

fn check(name: &str) {
    let input = corpus().join(name);
    let expect = expectation(&input);
    let dir = TempDir::new("bad");
    let scene = match input.extension().and_then(|e| e.to_str()) {
        Some("ply") => dir.write(
            "scene.xml",
            &format!(
                "<scene version=\"3.0.0\">\n<sensor type=\"perspective\"><float name=\"fov\" \
                 value=\"40\"/></sensor>\n<shape type=\"ply\"><string name=\"filename\" \
                 value=\"{}\"/></shape>\n</scene>\n",
                input.display()
            ),
        ),
        Some("serialized") => dir.write(
            "scene.xml",
            &format!(
                "<scene version=\"3.0.0\">\n<sensor type=\"perspective\"><float name=\"fov\" \
                 value=\"40\"/></sensor>\n<shape type=\"serialized\"><string name=\"filename\" \
                 value=\"{}\"/></shape>\n</scene>\n",
                input.display()
            ),
        ),
        Some("obj") => dir.write(
            "scene.toml",
            &format!(
                "[[camera]]\nname = \"c\"\ntype = \"perspective\"\norigin = [0, 0, 5]\n\
                 target = [0, 0, 0]\nup = [0, 1, 0]\nfov = 40\n\n[material.m]\n\
                 type = \"lambert\"\nalbedo = 0.5\n\n[[shape]]\ntype = \"mesh\"\n\
                 file = {:?}\nmaterial = \"m\"\n",
                input.display().to_string()
            ),
        ),
        Some("hdr") => dir.write(
            "scene.xml",
            &format!(
                "<scene version=\"3.0.0\">\n<sensor type=\"perspective\"><float name=\"fov\" \
                 value=\"40\"/></sensor>\n<emitter type=\"envmap\"><string name=\"filename\" \
                 value=\"{}\"/></emitter>\n</scene>\n",
                input.display()
            ),
        ),
        _ => input.clone(),
    };
    let out = dir.path().join("out.png");
    let mut cmd = std::process::Command::new(BIN);
    cmd.arg("render").arg(&scene).arg("-o").arg(&out);
    limit_memory(&mut cmd);
    let o = cmd.output().expect("cannot run the mcrt binary");
    let err = stderr_of(&o);
    assert!(!err.contains("panicked"), "{name}: mcrt panicked:\n{err}");
    assert_eq!(
        o.status.code(),
        Some(2),
        "{name}: exit status; stderr:\n{err}"
    );
    assert!(
        err.contains(name),
        "{name}: the message should name the file:\n{err}"
    );
    assert!(
        err.contains(&expect),
        "{name}: the message should say {expect:?}:\n{err}"
    );
    assert!(!out.exists(), "{name}: an output file was written");
    assert!(
        o.stdout.is_empty(),
        "{name}: nothing goes to stdout on failure"
    );
}

/// Bad inputs run under a 4 GiB address-space limit: one that makes mcrt allocate without
/// bound fails the test (out of memory) instead of the machine.
fn limit_memory(cmd: &mut std::process::Command) {
    #[cfg(target_os = "linux")]
    {
        use std::os::unix::process::CommandExt;
        // SAFETY: setrlimit is async-signal-safe; nothing else runs between fork and exec.
        unsafe {
            cmd.pre_exec(|| {
                let cap = 4 << 30;
                let lim = libc::rlimit {
                    rlim_cur: cap,
                    rlim_max: cap,
                };
                if libc::setrlimit(libc::RLIMIT_AS, &lim) != 0 {
                    return Err(std::io::Error::last_os_error());
                }
                Ok(())
            });
        }
    }
    #[cfg(not(target_os = "linux"))]
    let _ = cmd;
}

macro_rules! bad_input {
    ($test:ident, $file:expr) => {
        #[test]
        fn $test() {
            check($file);
        }
    };
}

bad_input!(obj_bad_number_obj, "obj-bad-number.obj");
bad_input!(obj_face_two_vertices_obj, "obj-face-two-vertices.obj");
bad_input!(obj_index_out_of_range_obj, "obj-index-out-of-range.obj");
bad_input!(obj_nan_vertex_obj, "obj-nan-vertex.obj");
bad_input!(obj_vertex_two_numbers_obj, "obj-vertex-two-numbers.obj");
bad_input!(ply_bad_magic_ply, "ply-bad-magic.ply");
bad_input!(
    ply_count_beyond_file_size_ply,
    "ply-count-beyond-file-size.ply"
);
bad_input!(ply_huge_vertex_count_ply, "ply-huge-vertex-count.ply");
bad_input!(ply_index_out_of_range_ply, "ply-index-out-of-range.ply");
bad_input!(ply_nan_vertex_ply, "ply-nan-vertex.ply");
bad_input!(ply_truncated_binary_ply, "ply-truncated-binary.ply");
bad_input!(ply_unknown_format_ply, "ply-unknown-format.ply");
bad_input!(toml_absurd_resolution_toml, "toml-absurd-resolution.toml");
bad_input!(toml_albedo_above_one_toml, "toml-albedo-above-one.toml");
bad_input!(
    toml_camera_eye_on_target_toml,
    "toml-camera-eye-on-target.toml"
);
bad_input!(toml_fov_zero_toml, "toml-fov-zero.toml");
bad_input!(toml_infinite_emission_toml, "toml-infinite-emission.toml");
bad_input!(
    toml_max_depth_minus_two_toml,
    "toml-max-depth-minus-two.toml"
);
bad_input!(
    toml_mesh_index_out_of_range_toml,
    "toml-mesh-index-out-of-range.toml"
);
bad_input!(toml_missing_mesh_file_toml, "toml-missing-mesh-file.toml");
bad_input!(toml_nan_albedo_toml, "toml-nan-albedo.toml");
bad_input!(toml_negative_ior_toml, "toml-negative-ior.toml");
bad_input!(
    toml_unknown_distribution_toml,
    "toml-unknown-distribution.toml"
);
bad_input!(toml_negative_radius_toml, "toml-negative-radius.toml");
bad_input!(toml_negative_width_toml, "toml-negative-width.toml");
bad_input!(
    toml_pinhole_missing_corner_toml,
    "toml-pinhole-missing-corner.toml"
);
bad_input!(
    toml_rr_survival_above_one_toml,
    "toml-rr-survival-above-one.toml"
);
bad_input!(
    toml_camera_up_nearly_parallel_toml,
    "toml-camera-up-nearly-parallel.toml"
);
bad_input!(
    toml_pinhole_identical_corners_toml,
    "toml-pinhole-identical-corners.toml"
);
bad_input!(
    toml_pinhole_collinear_corners_toml,
    "toml-pinhole-collinear-corners.toml"
);
bad_input!(
    toml_pinhole_eye_in_plane_toml,
    "toml-pinhole-eye-in-plane.toml"
);
bad_input!(
    toml_radius_overflows_f32_toml,
    "toml-radius-overflows-f32.toml"
);
bad_input!(
    toml_radius_underflows_f32_toml,
    "toml-radius-underflows-f32.toml"
);
bad_input!(toml_spp_too_large_toml, "toml-spp-too-large.toml");
bad_input!(
    toml_syntax_unclosed_table_toml,
    "toml-syntax-unclosed-table.toml"
);
bad_input!(
    toml_triangle_two_vertices_toml,
    "toml-triangle-two-vertices.toml"
);
bad_input!(
    toml_unknown_camera_type_toml,
    "toml-unknown-camera-type.toml"
);
bad_input!(toml_unknown_integrator_toml, "toml-unknown-integrator.toml");
bad_input!(
    toml_unknown_material_reference_toml,
    "toml-unknown-material-reference.toml"
);
bad_input!(
    toml_unknown_material_type_toml,
    "toml-unknown-material-type.toml"
);
bad_input!(
    toml_unknown_render_camera_toml,
    "toml-unknown-render-camera.toml"
);
bad_input!(toml_unknown_render_key_toml, "toml-unknown-render-key.toml");
bad_input!(toml_unknown_table_toml, "toml-unknown-table.toml");
bad_input!(toml_width_is_a_string_toml, "toml-width-is-a-string.toml");
bad_input!(toml_zero_area_light_toml, "toml-zero-area-light.toml");
bad_input!(toml_zero_spp_toml, "toml-zero-spp.toml");
bad_input!(xml_absurd_resolution_xml, "xml-absurd-resolution.xml");
bad_input!(xml_unknown_distribution_xml, "xml-unknown-distribution.xml");
bad_input!(xml_crop_outside_film_xml, "xml-crop-outside-film.xml");
bad_input!(xml_duplicate_id_xml, "xml-duplicate-id.xml");
bad_input!(xml_include_cycle_xml, "xml-include-cycle.xml");
bad_input!(xml_malformed_xml, "xml-malformed.xml");
bad_input!(xml_missing_include_xml, "xml-missing-include.xml");
bad_input!(xml_missing_obj_file_xml, "xml-missing-obj-file.xml");
bad_input!(xml_missing_reference_xml, "xml-missing-reference.xml");
bad_input!(xml_misspelt_property_xml, "xml-misspelt-property.xml");
bad_input!(xml_nan_radius_xml, "xml-nan-radius.xml");
bad_input!(xml_negative_colour_xml, "xml-negative-colour.xml");
bad_input!(xml_negative_radius_xml, "xml-negative-radius.xml");
bad_input!(xml_radius_overflows_f32_xml, "xml-radius-overflows-f32.xml");
bad_input!(xml_rgb_overflows_f32_xml, "xml-rgb-overflows-f32.xml");
bad_input!(xml_rgb_two_numbers_xml, "xml-rgb-two-numbers.xml");
bad_input!(xml_root_not_scene_xml, "xml-root-not-scene.xml");
bad_input!(
    xml_translate_overflows_f32_xml,
    "xml-translate-overflows-f32.xml"
);
bad_input!(xml_rotate_without_angle_xml, "xml-rotate-without-angle.xml");
bad_input!(
    xml_spectrum_by_wavelength_xml,
    "xml-spectrum-by-wavelength.xml"
);
bad_input!(
    xml_sphere_nonuniform_scale_xml,
    "xml-sphere-nonuniform-scale.xml"
);
bad_input!(xml_text_content_xml, "xml-text-content.xml");
bad_input!(xml_undefined_parameter_xml, "xml-undefined-parameter.xml");
bad_input!(xml_unknown_bsdf_xml, "xml-unknown-bsdf.xml");
bad_input!(xml_unknown_conductor_xml, "xml-unknown-conductor.xml");
bad_input!(xml_unknown_emitter_xml, "xml-unknown-emitter.xml");
bad_input!(xml_unknown_integrator_xml, "xml-unknown-integrator.xml");
bad_input!(xml_unknown_sensor_xml, "xml-unknown-sensor.xml");
bad_input!(xml_unknown_shape_xml, "xml-unknown-shape.xml");
bad_input!(xml_wrong_property_type_xml, "xml-wrong-property-type.xml");
bad_input!(xml_zero_area_emitter_xml, "xml-zero-area-emitter.xml");
bad_input!(
    xml_normalmap_without_bsdf_xml,
    "xml-normalmap-without-bsdf.xml"
);
bad_input!(
    xml_normalmap_without_texture_xml,
    "xml-normalmap-without-texture.xml"
);
bad_input!(xml_bumpmap_two_bsdfs_xml, "xml-bumpmap-two-bsdfs.xml");
bad_input!(
    xml_bumpmap_without_texture_xml,
    "xml-bumpmap-without-texture.xml"
);
bad_input!(
    xml_mask_opacity_above_one_xml,
    "xml-mask-opacity-above-one.xml"
);
bad_input!(
    xml_mask_negative_opacity_xml,
    "xml-mask-negative-opacity.xml"
);
bad_input!(xml_mask_emitter_child_xml, "xml-mask-emitter-child.xml");
bad_input!(
    xml_normalmap_texture_child_xml,
    "xml-normalmap-texture-child.xml"
);
bad_input!(xml_mask_in_mask_xml, "xml-mask-in-mask.xml");

/// Every file of the corpus has its test above, and the corpus is as large as promised.
#[test]
fn every_corpus_file_is_tested() {
    let listed = include_str!("bad_inputs.rs");
    let mut n = 0;
    for e in std::fs::read_dir(corpus()).unwrap() {
        let name = e.unwrap().file_name().to_string_lossy().into_owned();
        assert!(
            listed.contains(&format!("\"{name}\"")),
            "{name} has no test"
        );
        n += 1;
    }
    assert!(n >= 40, "only {n} bad inputs");
}

// Issue 27: bounds before work, checked arithmetic, messages.
bad_input!(xml_crop_overflow_xml, "xml-crop-overflow.xml");
bad_input!(xml_matrix_nan_xml, "xml-matrix-nan.xml");
bad_input!(xml_default_expansion_xml, "xml-default-expansion.xml");
bad_input!(
    xml_emitter_samples_above_limit_xml,
    "xml-emitter-samples-above-limit.xml"
);
bad_input!(
    xml_max_depth_above_limit_xml,
    "xml-max-depth-above-limit.xml"
);
bad_input!(
    toml_shadow_rays_above_limit_toml,
    "toml-shadow-rays-above-limit.toml"
);
bad_input!(
    toml_rr_depth_above_limit_toml,
    "toml-rr-depth-above-limit.toml"
);
bad_input!(
    toml_max_depth_above_limit_toml,
    "toml-max-depth-above-limit.toml"
);
bad_input!(
    toml_rr_survival_one_minus_ulp_toml,
    "toml-rr-survival-one-minus-ulp.toml"
);

// glTF 2.0 (written by tests/data/gltf/make_bad_inputs.py).
bad_input!(gltf_clearcoat_strict_gltf, "gltf-clearcoat-strict.gltf");
bad_input!(
    gltf_accessor_out_of_bounds_gltf,
    "gltf-accessor-out-of-bounds.gltf"
);
bad_input!(gltf_bad_json_gltf, "gltf-bad-json.gltf");
bad_input!(gltf_bad_reference_gltf, "gltf-bad-reference.gltf");
bad_input!(
    gltf_glb_length_too_small_glb,
    "gltf-glb-length-too-small.glb"
);
bad_input!(
    gltf_glb_without_bin_chunk_glb,
    "gltf-glb-without-bin-chunk.glb"
);
bad_input!(gltf_image_without_data_gltf, "gltf-image-without-data.gltf");
bad_input!(gltf_index_out_of_range_gltf, "gltf-index-out-of-range.gltf");
bad_input!(gltf_missing_buffer_gltf, "gltf-missing-buffer.gltf");
bad_input!(gltf_no_camera_gltf, "gltf-no-camera.gltf");
bad_input!(gltf_no_light_gltf, "gltf-no-light.gltf");
bad_input!(
    gltf_position_accessor_missing_gltf,
    "gltf-position-accessor-missing.gltf"
);
bad_input!(gltf_node_cycle_gltf, "gltf-node-cycle.gltf");
bad_input!(
    gltf_roughness_above_one_gltf,
    "gltf-roughness-above-one.gltf"
);
bad_input!(gltf_truncated_glb, "gltf-truncated.glb");
bad_input!(
    gltf_unsupported_extension_gltf,
    "gltf-unsupported-extension.gltf"
);
bad_input!(gltf_zero_yfov_gltf, "gltf-zero-yfov.gltf");
bad_input!(gltf_tangent_wrong_type_gltf, "gltf-tangent-wrong-type.gltf");
bad_input!(gltf_tangent_count_gltf, "gltf-tangent-count.gltf");
// Issue 25: cameras (thinlens, orthographic, focal_length), cylinder, serialized meshes.
bad_input!(
    serialized_bad_magic_serialized,
    "serialized-bad-magic.serialized"
);
bad_input!(
    serialized_corrupt_serialized,
    "serialized-corrupt.serialized"
);
bad_input!(
    serialized_index_out_of_range_serialized,
    "serialized-index-out-of-range.serialized"
);
bad_input!(
    serialized_truncated_serialized,
    "serialized-truncated.serialized"
);
bad_input!(
    serialized_version_5_serialized,
    "serialized-version-5.serialized"
);
bad_input!(xml_bad_focal_length_xml, "xml-bad-focal-length.xml");
bad_input!(xml_cylinder_zero_radius_xml, "xml-cylinder-zero-radius.xml");
bad_input!(xml_cylinder_same_points_xml, "xml-cylinder-same-points.xml");
bad_input!(xml_fov_and_focal_length_xml, "xml-fov-and-focal-length.xml");
bad_input!(
    xml_near_clip_beyond_far_clip_xml,
    "xml-near-clip-beyond-far-clip.xml"
);
bad_input!(
    xml_orthographic_flat_to_world_xml,
    "xml-orthographic-flat-to-world.xml"
);
bad_input!(
    xml_thinlens_negative_aperture_xml,
    "xml-thinlens-negative-aperture.xml"
);
bad_input!(
    xml_thinlens_without_aperture_xml,
    "xml-thinlens-without-aperture.xml"
);
bad_input!(
    xml_thinlens_zero_focus_distance_xml,
    "xml-thinlens-zero-focus-distance.xml"
);
bad_input!(
    xml_serialized_shape_index_out_of_range_xml,
    "xml-serialized-shape-index-out-of-range.xml"
);
bad_input!(
    xml_serialized_negative_shape_index_xml,
    "xml-serialized-negative-shape-index.xml"
);
bad_input!(
    toml_thinlens_negative_aperture_toml,
    "toml-thinlens-negative-aperture.toml"
);
bad_input!(
    toml_orthographic_zero_width_toml,
    "toml-orthographic-zero-width.toml"
);
bad_input!(
    toml_cylinder_same_points_toml,
    "toml-cylinder-same-points.toml"
);
// Spot and envmap emitters, and Radiance HDR (RGBE) images.
bad_input!(hdr_truncated_hdr, "hdr-truncated.hdr");
bad_input!(hdr_bad_orientation_hdr, "hdr-bad-orientation.hdr");
bad_input!(hdr_run_too_long_hdr, "hdr-run-too-long.hdr");
bad_input!(hdr_huge_size_hdr, "hdr-huge-size.hdr");
bad_input!(hdr_xyze_format_hdr, "hdr-xyze-format.hdr");
bad_input!(hdr_no_magic_hdr, "hdr-no-magic.hdr");
bad_input!(hdr_header_not_ended_hdr, "hdr-header-not-ended.hdr");
bad_input!(xml_envmap_missing_file_xml, "xml-envmap-missing-file.xml");
bad_input!(
    xml_envmap_negative_scale_xml,
    "xml-envmap-negative-scale.xml"
);
bad_input!(
    xml_envmap_skewed_to_world_xml,
    "xml-envmap-skewed-to-world.xml"
);
bad_input!(
    xml_spot_cutoff_out_of_range_xml,
    "xml-spot-cutoff-out-of-range.xml"
);
bad_input!(
    xml_spot_beam_wider_than_cutoff_xml,
    "xml-spot-beam-wider-than-cutoff.xml"
);
bad_input!(
    xml_spot_constant_texture_xml,
    "xml-spot-constant-texture.xml"
);
bad_input!(
    toml_envmap_negative_scale_toml,
    "toml-envmap-negative-scale.toml"
);
bad_input!(
    toml_envmap_missing_file_toml,
    "toml-envmap-missing-file.toml"
);
bad_input!(
    toml_spot_cutoff_out_of_range_toml,
    "toml-spot-cutoff-out-of-range.toml"
);
bad_input!(toml_spot_up_parallel_toml, "toml-spot-up-parallel.toml");
bad_input!(
    toml_spot_position_and_to_world_toml,
    "toml-spot-position-and-to-world.toml"
);
// Issue 25: the principled BSDFs' parameters (ranges, unknown names, eta or specular).
bad_input!(
    toml_principled_eta_and_specular_toml,
    "toml-principled-eta-and-specular.toml"
);
bad_input!(
    toml_principled_metallic_two_toml,
    "toml-principled-metallic-two.toml"
);
bad_input!(
    toml_principled_negative_sheen_toml,
    "toml-principled-negative-sheen.toml"
);
bad_input!(
    toml_principledthin_clearcoat_toml,
    "toml-principledthin-clearcoat.toml"
);
bad_input!(
    xml_principled_eta_and_specular_xml,
    "xml-principled-eta-and-specular.xml"
);
bad_input!(
    xml_principled_metallic_two_xml,
    "xml-principled-metallic-two.xml"
);
bad_input!(
    xml_principled_negative_eta_xml,
    "xml-principled-negative-eta.xml"
);
bad_input!(
    xml_principled_negative_roughness_xml,
    "xml-principled-negative-roughness.xml"
);
bad_input!(
    xml_principled_sampling_rate_negative_xml,
    "xml-principled-sampling-rate-negative.xml"
);
bad_input!(
    xml_principled_unknown_parameter_xml,
    "xml-principled-unknown-parameter.xml"
);
bad_input!(
    xml_principledthin_diff_trans_three_xml,
    "xml-principledthin-diff-trans-three.xml"
);
bad_input!(
    xml_principledthin_metallic_xml,
    "xml-principledthin-metallic.xml"
);
bad_input!(xml_texture_on_ior_xml, "xml-texture-on-ior.xml");
bad_input!(
    xml_texture_roughplastic_alpha_xml,
    "xml-texture-roughplastic-alpha.xml"
);
bad_input!(
    xml_blend_weight_above_one_xml,
    "xml-blend-weight-above-one.xml"
);
bad_input!(xml_blend_one_child_xml, "xml-blend-one-child.xml");
bad_input!(xml_blend_without_weight_xml, "xml-blend-without-weight.xml");
bad_input!(
    xml_blend_nested_too_deep_xml,
    "xml-blend-nested-too-deep.xml"
);
bad_input!(
    xml_blend_contains_itself_xml,
    "xml-blend-contains-itself.xml"
);
bad_input!(xml_unknown_wrap_mode_xml, "xml-unknown-wrap-mode.xml");
bad_input!(xml_unknown_filter_type_xml, "xml-unknown-filter-type.xml");
bad_input!(
    toml_blend_weight_below_zero_toml,
    "toml-blend-weight-below-zero.toml"
);
bad_input!(
    toml_blend_contains_itself_toml,
    "toml-blend-contains-itself.toml"
);
bad_input!(
    toml_blend_three_materials_toml,
    "toml-blend-three-materials.toml"
);
bad_input!(
    toml_texture_roughplastic_alpha_toml,
    "toml-texture-roughplastic-alpha.toml"
);
bad_input!(
    toml_unknown_roughness_texture_toml,
    "toml-unknown-roughness-texture.toml"
);
bad_input!(
    xml_instance_projective_to_world_xml,
    "xml-instance-projective-to-world.xml"
);
bad_input!(
    xml_instance_ref_not_shapegroup_xml,
    "xml-instance-ref-not-shapegroup.xml"
);
bad_input!(
    xml_instance_ref_to_plain_shape_xml,
    "xml-instance-ref-to-plain-shape.xml"
);
bad_input!(
    xml_instance_singular_to_world_xml,
    "xml-instance-singular-to-world.xml"
);
bad_input!(
    xml_instance_two_shapegroups_xml,
    "xml-instance-two-shapegroups.xml"
);
bad_input!(xml_instance_unknown_id_xml, "xml-instance-unknown-id.xml");
bad_input!(
    xml_instance_without_shapegroup_xml,
    "xml-instance-without-shapegroup.xml"
);
bad_input!(
    xml_shapegroup_bsdf_child_xml,
    "xml-shapegroup-bsdf-child.xml"
);
bad_input!(xml_shapegroup_emitter_xml, "xml-shapegroup-emitter.xml");
bad_input!(xml_shapegroup_nested_xml, "xml-shapegroup-nested.xml");
bad_input!(
    xml_shapegroup_with_instance_xml,
    "xml-shapegroup-with-instance.xml"
);
bad_input!(toml_group_emission_toml, "toml-group-emission.toml");
bad_input!(
    toml_instance_matrix_and_scale_toml,
    "toml-instance-matrix-and-scale.toml"
);
bad_input!(toml_instance_singular_toml, "toml-instance-singular.toml");
bad_input!(
    toml_instance_unknown_group_toml,
    "toml-instance-unknown-group.toml"
);
