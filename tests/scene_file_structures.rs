//! `[[structures]]`, `[[projectiles]]`, prototype colours and environment collider cells in
//! scene files: what they parse into, how `--count` scales them, and bad input, which is an
//! error naming the file, the line and the field, never a panic.

use crate::common;

use common::scene_errors::{expect_error, parse};
use common::scenes;
use dormant::scene::file::spec::{ProjectileAim, StructureLayout};
use dormant::scene::file::{SceneError, SceneFile};
use proptest::prelude::*;

const GOOD: &str = r#"[scene]
name = "t"
frames = 100

[environment]
generator = "ground"

[[prototypes]]
name = "brick"
shape = "box"
half_extents = [0.2, 0.1, 0.1]
color = [0.7, 0.2, 0.1]

[[prototypes]]
name = "ball"
shape = "sphere"
radius = 0.3

[[structures]]
name = "towers"
kind = "tower"
prototype = "brick"
layers = 5
per_layer = 2
origin = [1.0, 0.0, 2.0]
array = { counts = [3, 2], spacing = [4.0, 5.0] }

[[projectiles]]
prototype = "ball"
structure = "towers"
frame = 10
interval_frames = 20
position = [0.0, 1.0, -2.0]
velocity = [0.0, 0.0, 8.0]
"#;

#[test]
fn structures_and_projectiles_parse_into_checked_tables() {
    let file = parse(GOOD).unwrap();
    let spec = file.spec();
    let towers = &spec.structures[0];
    assert_eq!(towers.prototype, 0);
    assert_eq!(towers.half_extents, [0.2, 0.1, 0.1]);
    assert_eq!(towers.layout, StructureLayout::Tower { layers: 5, per_layer: 2 });
    assert_eq!(towers.copies(), 6);
    assert_eq!(towers.body_count(), 60);
    assert_eq!(spec.projectiles[0].aim, ProjectileAim::Structure { structure: 0, every: 1, count: None });
    assert_eq!(spec.prototypes[0].color, Some([0.7, 0.2, 0.1]));
    assert_eq!(spec.prototypes[1].color, None);
    assert_eq!(spec.environment.collider_cells, 1);
    // One launch at every copy, 20 frames apart, until the run ends.
    let launches = spec.projectiles[0].launches(&spec.structures, spec.scene.frames);
    assert_eq!(launches.iter().map(|l| l.frame).collect::<Vec<_>>(), vec![10, 30, 50, 70, 90]);
    assert_eq!(launches[1].translation, glam::Vec3::new(5.0, 1.0, 0.0), "copy 1 is 4 m along X");
}

#[test]
fn a_structure_needs_a_box_prototype_that_exists() {
    let text = GOOD.replace("prototype = \"brick\"", "prototype = \"ball\"");
    let err = expect_error(&text, "structures[0].prototype", Some(22));
    assert!(err.to_string().contains("not a box"), "{err}");
    let text = GOOD.replace("prototype = \"brick\"", "prototype = \"slab\"");
    expect_error(&text, "structures[0].prototype", Some(22));
}

#[test]
fn a_structure_takes_exactly_the_layout_keys_of_its_kind() {
    let missing = GOOD.replace("per_layer = 2\n", "");
    expect_error(&missing, "structures[0].per_layer", Some(19));
    let foreign = GOOD.replace("per_layer = 2", "per_layer = 2\nspacing = 0.5");
    expect_error(&foreign, "structures[0].spacing", Some(25));
    let grid = GOOD
        .replace("kind = \"tower\"", "kind = \"grid\"")
        .replace("layers = 5\nper_layer = 2", "counts = [2, 0, 2]");
    expect_error(&grid, "structures[0].counts", Some(23));
    let unknown = GOOD.replace("kind = \"tower\"", "kind = \"pyramid\"");
    let err = expect_error(&unknown, "structures.kind", Some(21));
    assert!(matches!(err, SceneError::Syntax { .. }));
}

#[test]
fn structure_counts_and_sizes_are_checked() {
    expect_error(&GOOD.replace("layers = 5", "layers = 0"), "structures[0].layers", Some(23));
    expect_error(
        &GOOD.replace("origin = [1.0, 0.0, 2.0]", "gap = -0.1\norigin = [1.0, 0.0, 2.0]"),
        "structures[0].gap",
        Some(25),
    );
    expect_error(&GOOD.replace("[1.0, 0.0, 2.0]", "[1.0, nan, 2.0]"), "structures[0].origin", Some(25));
    expect_error(&GOOD.replace("counts = [3, 2]", "counts = [3, 0]"), "structures[0].array.counts", Some(26));
    // Copies beyond the body budget are refused at the array; blocks x copies beyond it at
    // the structure.
    let huge = GOOD.replace("counts = [3, 2]", "counts = [100000, 1000]");
    let err = expect_error(&huge, "structures[0].array.counts", Some(26));
    assert!(err.to_string().contains("2000000 bodies"), "{err}");
    let huge = GOOD.replace("counts = [3, 2]", "counts = [1000, 1000]");
    let err = expect_error(&huge, "structures[0]", Some(19));
    assert!(err.to_string().contains("bodies"), "{err}");
    let duplicate = format!(
        "{GOOD}\n{}",
        &GOOD[GOOD.find("[[structures]]").unwrap()..GOOD.find("[[projectiles]]").unwrap()]
    );
    expect_error(&duplicate, "structures[1].name", Some(37));
}

#[test]
fn copies_that_would_touch_are_rejected() {
    // A tower of two 0.4 m bricks side by side is 0.4 x 0.4 m: copies 0.3 m apart overlap.
    let err = expect_error(
        &GOOD.replace("spacing = [4.0, 5.0]", "spacing = [0.3, 5.0]"),
        "structures[0].array.spacing",
        Some(26),
    );
    assert!(err.to_string().contains("touch"), "{err}");
    // Along an axis with one copy the spacing does not matter.
    parse(&GOOD.replace("counts = [3, 2], spacing = [4.0, 5.0]", "counts = [3, 1], spacing = [4.0, 0.0]"))
        .unwrap();
}

#[test]
fn copies_of_different_structures_must_not_overlap() {
    let second =
        "\n[[structures]]\nname = \"stack\"\nkind = \"grid\"\nprototype = \"brick\"\ncounts = [2, 2, 2]\n";
    // The towers' copies stand at x = 1, 5, 9 and z = 2, 7: a stack at x = 5.2 overlaps one.
    let text = format!("{GOOD}{second}origin = [5.2, 0.0, 7.0]\n");
    let err = expect_error(&text, "structures[1].origin", Some(41));
    assert!(err.to_string().contains("copy 4 of \"towers\""), "{err}");
    parse(&format!("{GOOD}{second}origin = [3.0, 0.0, 7.0]\n")).unwrap();
}

#[test]
fn dominoes_must_not_overlap() {
    let dominoes = GOOD
        .replace("kind = \"tower\"", "kind = \"dominoes\"")
        .replace("layers = 5\nper_layer = 2", "count = 10\nspacing = 0.15");
    let err = expect_error(&dominoes, "structures[0].spacing", Some(24));
    assert!(err.to_string().contains("overlap"), "{err}");
    let spec = parse(&dominoes.replace("spacing = 0.15", "spacing = 0.5")).unwrap().spec().clone();
    assert_eq!(spec.structures[0].layout, StructureLayout::Dominoes { count: 10, spacing: 0.5 });
}

#[test]
fn projectiles_are_checked() {
    expect_error(
        &GOOD.replace("structure = \"towers\"", "structure = \"walls\""),
        "projectiles[0].structure",
        Some(30),
    );
    expect_error(
        &GOOD.replace("prototype = \"ball\"\nstructure", "prototype = \"rock\"\nstructure"),
        "projectiles[0].prototype",
        Some(29),
    );
    expect_error(&GOOD.replace("frame = 10", "frame = 100"), "projectiles[0].frame", Some(31));
    expect_error(
        &GOOD.replace("interval_frames = 20", "interval_frames = 20\nstep = [1.0, 0.0, 0.0]"),
        "projectiles[0].step",
        Some(33),
    );
    let world = GOOD.replace("structure = \"towers\"\n", "");
    let spec = parse(&world).unwrap().spec().clone();
    assert_eq!(spec.projectiles[0].aim, ProjectileAim::World { count: 1, step: [0.0; 3] });
    expect_error(&world.replace("frame = 10", "every = 2\nframe = 10"), "projectiles[0].every", Some(30));
    expect_error(&GOOD.replace("frame = 10", "count = 0\nframe = 10"), "projectiles[0].count", Some(31));
    expect_error(&GOOD.replace("[0.0, 0.0, 8.0]", "[0.0, inf, 8.0]"), "projectiles[0].velocity", Some(34));
}

#[test]
fn prototype_colours_and_collider_cells_are_checked() {
    expect_error(&GOOD.replace("[0.7, 0.2, 0.1]", "[1.7, 0.2, 0.1]"), "prototypes[0].color", Some(12));
    let cells = GOOD.replace("generator = \"ground\"", "generator = \"ground\"\ncollider_cells = 0");
    expect_error(&cells, "environment.collider_cells", Some(7));
    let cells = GOOD.replace("generator = \"ground\"", "generator = \"ground\"\ncollider_cells = 8");
    assert_eq!(parse(&cells).unwrap().spec().environment.collider_cells, 8);
}

#[test]
fn count_override_scales_structures_by_whole_copies() {
    let file = parse(GOOD).unwrap();
    // 60 bodies in 6 copies of 10; about 200 bodies is 20 copies, in the array's 3:2 shape.
    let big = file.clone().with_total_count(200).unwrap();
    assert_eq!(big.spec().structures[0].array.counts, [5, 4]);
    assert_ne!(big.source_hash(), file.source_hash(), "the override is folded into the hash");
    let tiny = file.with_total_count(1).unwrap();
    assert_eq!(tiny.spec().structures[0].array.counts, [1, 1], "at least one copy");
    let spec = tiny.spec();
    assert_eq!(
        spec.projectiles[0].launches(&spec.structures, spec.scene.frames).len(),
        1,
        "projectiles follow the copies"
    );
}

#[test]
fn count_override_refuses_arrays_that_grow_into_other_structures() {
    // The towers' copies stand at x = 1, 5, 9 and would grow to 13: a stack stands at x = 13.1.
    let text = format!(
        "{GOOD}\n[[structures]]\nname = \"stack\"\nkind = \"grid\"\nprototype = \"brick\"\ncounts = [1, 1, 1]\norigin = [13.1, 0.0, 2.0]\n"
    );
    let file = parse(&text).unwrap();
    file.clone().with_total_count(100).unwrap();
    let err = file.with_total_count(400).unwrap_err();
    let message = err.to_string();
    assert!(message.contains("scenes/bad.toml") && message.contains("--count 400"), "{message}");
    assert_eq!(err.field(), Some("structures[1].origin"), "{message}");
}

#[test]
fn the_demolition_scene_has_its_regime_and_scales_with_count() {
    let file = scenes::load("demolition");
    let bodies: u64 = file.spec().structures.iter().map(|s| s.body_count()).sum();
    assert!(bodies >= 50_000, "the paper's regime needs at least 50,000 bodies, has {bodies}");
    assert!(file.spec().structures.iter().all(|s| s.copies() > 1));
    let small = file.with_total_count(2000).unwrap();
    let scaled: u64 = small.spec().structures.iter().map(|s| s.body_count()).sum();
    assert!((1500..=2600).contains(&scaled), "--count 2000 gives {scaled} structure bodies");
    // The districts grow away from each other: the regime map's largest count lays out.
    let file = scenes::load("demolition");
    let large = file.with_total_count(300_000).unwrap();
    let scaled: u64 = large.spec().structures.iter().map(|s| s.body_count()).sum();
    assert!((270_000..=330_000).contains(&scaled), "--count 300000 gives {scaled} structure bodies");
}

fn layout_strategy() -> impl Strategy<Value = String> {
    prop_oneof![
        (1u32..12, 1u32..5).prop_map(|(l, p)| format!("kind = \"tower\"\nlayers = {l}\nper_layer = {p}")),
        (1u32..12, 1u32..9).prop_map(|(l, p)| format!("kind = \"wall\"\nlayers = {l}\nper_layer = {p}")),
        (1u32..30, 0.25f32..1.0)
            .prop_map(|(c, s)| format!("kind = \"dominoes\"\ncount = {c}\nspacing = {s}")),
        (1u32..5, 1u32..5, 1u32..5)
            .prop_map(|(x, y, z)| format!("kind = \"grid\"\ncounts = [{x}, {y}, {z}]")),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    /// Any layout, gap, heading and array that validation accepts: no two blocks of a copy
    /// overlap (in the copy's frame, where blocks are axis-aligned), every block rests on the
    /// ground or on blocks, and copies' footprints are apart.
    #[test]
    fn accepted_structures_have_blocks_that_do_not_overlap_and_copies_apart(
        layout in layout_strategy(),
        half in (0.05f32..0.5, 0.05f32..0.3, 0.02f32..0.2),
        gap in prop_oneof![Just(0.0f32), 0.0f32..0.05],
        yaw in -180.0f32..180.0,
        counts in (1u32..4, 1u32..4),
        spacing in (0.5f32..8.0, 0.5f32..8.0),
    ) {
        let text = format!(
            "[scene]\nname = \"p\"\nframes = 10\n[environment]\ngenerator = \"ground\"\n\
             [[prototypes]]\nname = \"b\"\nshape = \"box\"\nhalf_extents = [{}, {}, {}]\n\
             [[structures]]\nname = \"s\"\nprototype = \"b\"\n{layout}\ngap = {gap}\nyaw_degrees = {yaw}\n\
             array = {{ counts = [{}, {}], spacing = [{}, {}] }}\n",
            half.0, half.1, half.2, counts.0, counts.1, spacing.0, spacing.1
        );
        let Ok(file) = SceneFile::parse("p.toml", text) else { return Ok(()) };
        let s = &file.spec().structures[0];
        let h = glam::Vec3::from_array(s.half_extents);
        let boxes: Vec<(glam::Vec3, glam::Vec3)> = s
            .local_blocks()
            .into_iter()
            .map(|(c, yaw)| {
                let (sin, cos) = (yaw.sin().abs(), yaw.cos().abs());
                (c, glam::Vec3::new(cos * h.x + sin * h.z, h.y, sin * h.x + cos * h.z))
            })
            .collect();
        for (i, (a, ha)) in boxes.iter().enumerate() {
            prop_assert!(a.y - ha.y > -1e-5, "block {i} under the ground");
            let resting = (a.y - ha.y).abs() < 1e-4
                || boxes.iter().any(|(b, hb)| ((b.y + hb.y) - (a.y - ha.y)).abs() < 1e-4 + s.gap);
            prop_assert!(resting, "block {i} floats");
            for (b, hb) in &boxes[i + 1..] {
                let apart = (0..3).any(|k| (a[k] - b[k]).abs() >= ha[k] + hb[k] - 1e-4);
                prop_assert!(apart, "blocks overlap: {a} {b}");
            }
        }
        let size = s.footprint().size();
        for copy in 1..s.copies() {
            let (anchor, _) = s.copy_placement(copy);
            let (first, rotation) = s.copy_placement(0);
            let local = rotation.inverse() * (anchor - first);
            prop_assert!(local.x.abs() > size[0] - 1e-3 || local.z.abs() > size[1] - 1e-3, "copy {copy} touches copy 0");
        }
    }

    /// `--count` on a scene with structures: every structure keeps at least one copy, and
    /// the total is within a copy per structure of what was asked (or the one-copy floor).
    #[test]
    fn count_override_lands_within_a_copy_of_the_total(total in 1u32..5000, towers in (1u32..20, 1u32..20)) {
        let text = GOOD
            .replace("counts = [3, 2]", &format!("counts = [{}, {}]", towers.0, towers.1));
        let file = parse(&text).unwrap().with_total_count(total).unwrap();
        let s = &file.spec().structures[0];
        prop_assert!(s.copies() >= 1);
        let per_copy = s.layout.blocks_per_copy();
        let error = s.body_count().abs_diff(total as u64);
        // Rounding to whole copies, then to a grid of the array's shape.
        let slack = per_copy * (1 + 2 * (s.array.counts[0].max(s.array.counts[1]) as u64));
        prop_assert!(error <= slack || s.copies() == 1, "asked {total}, got {} ({:?})", s.body_count(), s.array.counts);
    }
}
