//! `dormant export --gltf`: the whole sequence as one animated glTF binary (format
//! `dormant-gltf-1`, docs/design.md): read back with the `gltf` crate, its meshes are
//! dormant's, its key frames give dormant's pose of every body at every frame with a resting
//! stretch kept as two keys, absent bodies are scaled to 0, and a second export is the same
//! file.

use crate::common;

use std::path::Path;

use common::cli::{dormant, exits_with, read_json, simulate_tiny, succeeds};
use dormant::sequence::{Sequence, SequenceSource};

/// Seconds of frame `i` as the export keys it (`sequence::gltf_export::frame_time`).
fn frame_time(i: u32, fps: f64) -> f32 {
    (i as f64 / fps) as f32
}

/// Every body's pose (`[tx, ty, tz, qx, qy, qz, qw]`, `None` while absent) by frame, as
/// dormant replays the trajectory.
fn poses(sequence: &Sequence) -> Vec<Vec<Option<[f32; 7]>>> {
    let all = sequence.select(None, Some(1)).unwrap();
    sequence.export(&all).frames.into_iter().map(|f| f.poses).collect()
}

/// Body `b`'s pose at frame `i`, absent frames holding the nearest present pose (the earlier
/// on a tie).
fn held_pose(poses: &[Vec<Option<[f32; 7]>>], b: usize, i: usize) -> [f32; 7] {
    (0..poses.len())
        .flat_map(|d| [i.checked_sub(d), Some(i + d)])
        .flatten()
        .find_map(|j| poses.get(j).and_then(|f| f[b]))
        .unwrap_or([0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0])
}

fn bits<const N: usize>(v: [f32; N]) -> [u32; N] {
    v.map(f32::to_bits)
}

/// The key frames (from the key times) and values of `node`'s channel `path`.
fn channel(
    doc: &gltf::Document,
    buffers: &[gltf::buffer::Data],
    node: usize,
    path: gltf::animation::Property,
    fps: f64,
) -> Vec<(usize, Vec<f32>)> {
    use gltf::animation::util::ReadOutputs;
    let animation = doc.animations().next().unwrap();
    let ch = animation
        .channels()
        .find(|c| c.target().node().index() == node && c.target().property() == path)
        .unwrap();
    let reader = ch.reader(|b| Some(&buffers[b.index()]));
    let frames: Vec<usize> = reader
        .read_inputs()
        .unwrap()
        .map(|t| {
            let i = (t as f64 * fps).round() as u32;
            assert_eq!(frame_time(i, fps).to_bits(), t.to_bits(), "key time {t} is frame_time({i})");
            i as usize
        })
        .collect();
    let values: Vec<Vec<f32>> = match reader.read_outputs().unwrap() {
        ReadOutputs::Translations(t) => t.map(|v| v.to_vec()).collect(),
        ReadOutputs::Rotations(r) => r.into_f32().map(|v| v.to_vec()).collect(),
        ReadOutputs::Scales(s) => s.map(|v| v.to_vec()).collect(),
        ReadOutputs::MorphTargetWeights(_) => unreachable!(),
    };
    assert_eq!(frames.len(), values.len());
    frames.into_iter().zip(values).collect()
}

/// `keys` (of a LINEAR channel) give `expected(i)` at every frame: exactly at a key, and
/// between two keys only across a stretch where both keys and every frame between are the
/// same; no key sits inside such a stretch. Returns whether a stretch of 3+ frames was seen.
fn check_linear(keys: &[(usize, Vec<f32>)], frames: usize, expected: impl Fn(usize) -> Vec<f32>) -> bool {
    let same = |a: &[f32], b: &[f32]| a.iter().map(|x| x.to_bits()).eq(b.iter().map(|x| x.to_bits()));
    assert_eq!(keys.first().unwrap().0, 0);
    assert_eq!(keys.last().unwrap().0, frames - 1);
    let mut stretch = false;
    for pair in keys.windows(2) {
        let ((a, va), (b, vb)) = (&pair[0], &pair[1]);
        assert!(same(va, &expected(*a)), "key at frame {a}: {va:?}, dormant {:?}", expected(*a));
        if b - a > 1 {
            stretch = true;
            assert!(same(va, vb), "frames {a}..={b} between two different keys");
            assert!((a + 1..*b).all(|i| same(&expected(i), va)), "frames {a}..={b} are not one pose");
        }
    }
    let (last, v) = keys.last().unwrap();
    assert!(same(v, &expected(*last)));
    for (i, _) in &keys[1..keys.len() - 1] {
        let inside = same(&expected(i - 1), &expected(*i)) && same(&expected(*i), &expected(i + 1));
        assert!(!inside, "frame {i} is keyed inside a stretch of one pose");
    }
    stretch
}

fn export(traj: &Path, extra: &[&std::ffi::OsStr]) {
    succeeds(dormant().args(["--quiet", "export", "--trajectory"]).arg(traj).args(extra));
}

#[test]
fn export_gltf_holds_every_frame_of_every_body_and_is_reproducible() {
    let dir = tempfile::TempDir::new().unwrap();
    let traj = simulate_tiny(dir.path(), &[]);
    let (glb, json) = (dir.path().join("tiny.glb"), dir.path().join("tiny.json"));
    export(&traj, &["--gltf".as_ref(), glb.as_ref(), "--out".as_ref(), json.as_ref()]);
    assert_eq!(read_json(&json)["format"], "dormant-export-1", "--out and --gltf write both");
    let sequence =
        Sequence::load(SequenceSource::Recorded { trajectory: traj.clone(), count: None }, &mut |_| {})
            .unwrap();
    let (doc, buffers, _) = gltf::import(&glb).unwrap();
    let extras: serde_json::Value =
        serde_json::from_str(doc.as_json().asset.extras.as_ref().unwrap().get()).unwrap();
    let d = &extras["dormant"];
    assert_eq!(d["format"], "dormant-gltf-1");
    assert_eq!(d["frames"], sequence.frame_count());
    let fps = d["fps"].as_f64().unwrap();
    assert_eq!(fps, 1.0 / sequence.trajectory.timestep as f64);
    // The scene TOML keeps cameras, lights and render settings, not what the file holds.
    let scene = d["scene"].as_str().unwrap();
    assert!(
        scene.contains("[[cameras]]") && scene.contains("[render]") && scene.contains("[scene]"),
        "{scene}"
    );
    assert!(
        !scene.contains("[physics]") && !scene.contains("[[spawners]]") && !scene.contains("frames ="),
        "{scene}"
    );

    let bodies = sequence.trajectory.bodies.len();
    let lights = 1 + sequence.template.lights.len();
    assert_eq!(doc.nodes().count(), bodies + 2 + lights, "bodies, environment, camera, sun and lights");
    assert_eq!(doc.scenes().next().unwrap().nodes().count(), doc.nodes().count());
    check_meshes(&doc, &buffers, &sequence);
    check_animation(&doc, &buffers, &sequence, fps);

    let again = dir.path().join("again.glb");
    export(&traj, &["--gltf".as_ref(), again.as_ref()]);
    assert!(std::fs::read(&glb).unwrap() == std::fs::read(&again).unwrap(), "a second export differs");
}

/// Mesh `i` is prototype `i` (then the environment), positions bit-exact, triangles in order.
fn check_meshes(doc: &gltf::Document, buffers: &[gltf::buffer::Data], sequence: &Sequence) {
    let assets = &sequence.assets;
    let expected: Vec<(&str, &dormant::geometry::TriangleMesh)> = (assets.prototypes.iter())
        .map(|(n, m)| (n.as_str(), m))
        .chain([("environment", &assets.environment)])
        .collect();
    assert_eq!(doc.meshes().count(), expected.len());
    for (mesh, (name, dormant_mesh)) in doc.meshes().zip(expected) {
        assert_eq!(mesh.name(), Some(name));
        let mut triangles = Vec::new();
        for p in mesh.primitives() {
            let reader = p.reader(|b| Some(&buffers[b.index()]));
            let positions: Vec<[f32; 3]> = reader.read_positions().unwrap().collect();
            let dormant_positions: Vec<[f32; 3]> =
                dormant_mesh.positions.iter().map(|v| v.to_array()).collect();
            assert!(positions.iter().map(|p| bits(*p)).eq(dormant_positions.iter().map(|p| bits(*p))));
            let indices: Vec<u32> = reader.read_indices().unwrap().into_u32().collect();
            triangles.extend(indices.chunks(3).map(|t| [t[0], t[1], t[2]]));
        }
        assert_eq!(triangles, dormant_mesh.indices, "{name}: triangles in dormant's order");
    }
}

/// Every body node's channels against dormant's replayed poses and presence.
fn check_animation(doc: &gltf::Document, buffers: &[gltf::buffer::Data], sequence: &Sequence, fps: f64) {
    use gltf::animation::Property;
    let poses = poses(sequence);
    let frames = poses.len();
    let (mut stretches, mut absent_frames) = (0, 0);
    for (b, body) in sequence.trajectory.bodies.iter().enumerate() {
        let node = doc.nodes().nth(b).unwrap();
        assert_eq!(node.name(), Some(format!("body {b}").as_str()));
        assert_eq!(node.mesh().unwrap().index(), body.prototype as usize);
        let extras: serde_json::Value = serde_json::from_str(node.extras().as_ref().unwrap().get()).unwrap();
        assert_eq!(extras["dormant"]["body"], b);
        let translation = channel(doc, buffers, b, Property::Translation, fps);
        let rotation = channel(doc, buffers, b, Property::Rotation, fps);
        // One key list for the pose: translation and rotation keyed at the same frames.
        assert!(translation.iter().map(|k| k.0).eq(rotation.iter().map(|k| k.0)), "body {b}");
        let pose_keys: Vec<(usize, Vec<f32>)> =
            translation.into_iter().zip(rotation).map(|((i, t), (_, r))| (i, [t, r].concat())).collect();
        stretches += usize::from(check_linear(&pose_keys, frames, |i| held_pose(&poses, b, i).to_vec()));
        let scale = channel(doc, buffers, b, Property::Scale, fps);
        assert_eq!(scale[0].0, 0);
        for (i, frame) in poses.iter().enumerate() {
            let value = &scale.iter().rev().find(|(k, _)| *k <= i).unwrap().1;
            let present = frame[b].is_some();
            absent_frames += usize::from(!present);
            assert_eq!(value, &vec![f32::from(u8::from(present)); 3], "body {b} frame {i}");
        }
        assert!(scale.windows(2).all(|w| w[0].1 != w[1].1), "body {b}: a scale key without a change");
    }
    assert!(stretches > 0, "tiny's bodies come to rest: some stretch keeps two keys");
    assert!(absent_frames > 0, "tiny's second wave spawns late: some frames have absent bodies");
}

#[test]
fn export_gltf_to_a_bad_path_fails_clearly_and_leaves_no_file() {
    let dir = tempfile::TempDir::new().unwrap();
    let traj = simulate_tiny(dir.path(), &[]);
    let missing = dir.path().join("missing").join("out.glb");
    let stderr =
        exits_with(dormant().args(["export", "--trajectory"]).arg(&traj).arg("--gltf").arg(&missing), 1);
    assert!(stderr.contains("cannot write") && stderr.contains("out.glb"), "{stderr}");
    // A directory in the way: the rename fails, and the temporary file goes too.
    let taken = dir.path().join("taken.glb");
    std::fs::create_dir(&taken).unwrap();
    let stderr =
        exits_with(dormant().args(["export", "--trajectory"]).arg(&traj).arg("--gltf").arg(&taken), 1);
    assert!(stderr.contains("taken.glb"), "{stderr}");
    let mut left: Vec<String> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    left.sort();
    assert_eq!(left, ["taken.glb", "tiny.traj"]);
    let stderr = exits_with(
        dormant()
            .args(["export", "--trajectory"])
            .arg(&traj)
            .args(["--frames", "0..10", "--gltf"])
            .arg(&missing),
        2,
    );
    assert!(stderr.contains("--frames"), "{stderr}");
}

/// A glTF prototype's materials and textures (the duck's base colour texture) come back
/// identical through dormant's own glTF import. Skips without `../shared/assets`.
#[test]
fn export_gltf_materials_and_textures_import_back_identical() {
    let Some(assets) = common::shared_assets() else { return };
    let dir = tempfile::TempDir::new().unwrap();
    let scene = dir.path().join("ducks.toml");
    let text = format!(
        "[scene]\nname = \"ducks\"\nframes = 20\nassets = {:?}\n\n[environment]\ngenerator = \"ground\"\n\n\
         [[prototypes]]\nname = \"duck\"\nshape = \"gltf\"\ngltf = \"duck.glb\"\nscale = 0.5\n\n\
         [[prototypes]]\nname = \"crate\"\nshape = \"box\"\nhalf_extents = [0.2, 0.2, 0.2]\n\n\
         [[spawners]]\nprototypes = [\"duck\", \"crate\"]\ncount = 4\n\
         region = {{ min = [-1.0, 1.0, -1.0], max = [1.0, 1.0, 1.0] }}\n",
        assets.to_str().unwrap()
    );
    std::fs::write(&scene, text).unwrap();
    let file = dormant::scene::file::SceneFile::load(&scene).unwrap();
    let source = SequenceSource::scene(file, dormant::physics::SimulateOptions::default(), None);
    let sequence = Sequence::load(source, &mut |_| {}).unwrap();
    let glb = dir.path().join("ducks.glb");
    sequence.write_gltf(&glb).unwrap();
    let back = dormant::scene::gltf::load_gltf(&glb).unwrap();
    let template = &sequence.template;
    assert_eq!(back.materials.len(), template.materials.len());
    assert!(!template.textures.is_empty(), "the duck has a base colour texture");
    let texture =
        |t: Option<u32>, all: &[&dormant::scene::texture::Texture]| t.map(|i| all[i as usize].clone());
    let exported: Vec<_> = template.textures.iter().map(|t| t.as_ref()).collect();
    let imported: Vec<_> = back.textures.iter().collect();
    for (m, original) in back.materials.iter().zip(&template.materials) {
        let plain = |m: &dormant::scene::Material| dormant::scene::Material {
            base_color_texture: None,
            metallic_roughness_texture: None,
            emissive_texture: None,
            ..*m
        };
        assert_eq!(plain(m), plain(original));
        for (a, b) in [
            (m.base_color_texture, original.base_color_texture),
            (m.metallic_roughness_texture, original.metallic_roughness_texture),
            (m.emissive_texture, original.emissive_texture),
        ] {
            let (a, b) = (texture(a, &imported), texture(b, &exported));
            // Names differ (the image's file); texels and wrap modes do not.
            assert_eq!(a.map(|t| (t.texels, t.wrap_s, t.wrap_t)), b.map(|t| (t.texels, t.wrap_s, t.wrap_t)));
        }
    }
}

#[test]
fn exported_lights_are_photometric_for_other_tools_and_exact_for_dormant() {
    let dir = tempfile::TempDir::new().unwrap();
    let file = common::scenes::load("tiny");
    let source = SequenceSource::scene(file, dormant::physics::SimulateOptions::default(), None);
    let sequence = Sequence::load(source, &mut |_| {}).unwrap();
    let glb = dir.path().join("tiny.glb");
    sequence.write_gltf(&glb).unwrap();
    let sun = sequence.template.sun.irradiance;
    // Other tools read lux: the sun's peak times 683 lm/W.
    let (doc, _, _) = gltf::import(&glb).unwrap();
    let light = doc.lights().unwrap().next().expect("the sun is the first light");
    assert_eq!(light.intensity(), sun.max_element() * 683.0);
    // dormant reads its own value back bit for bit, not lux / 683.
    let back = dormant::scene::gltf::load_gltf(&glb).unwrap();
    match back.lights[0] {
        dormant::scene::Light::Directional { irradiance, .. } => {
            assert_eq!(irradiance.to_array().map(f32::to_bits), sun.to_array().map(f32::to_bits))
        }
        ref other => panic!("the sun came back as {other:?}"),
    }
}
