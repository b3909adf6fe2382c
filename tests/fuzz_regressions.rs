//! Inputs the fuzzers found (docs/fuzzing.md), replayed through the code the fuzz targets run
//! (`tests/fuzz_harness`): each one, kept in `tests/data/fuzz/TARGET/` under the name of the
//! bug it found, is now rejected with an error naming the element and the cause. Every kept
//! input and every input of the committed corpora (`fuzz/corpus/TARGET/`) goes through its
//! target without panicking, and the generated seeds are accepted (so they reach past the
//! parsers' first checks).

use crate::fuzz_harness;

use std::path::{Path, PathBuf};

type Harness = fn(&[u8]) -> Result<(), String>;

const TARGETS: [(&str, Harness); 6] = [
    ("scene_toml", fuzz_harness::scene_toml),
    ("gltf_glb", fuzz_harness::gltf_glb),
    ("gltf_json", fuzz_harness::gltf_json),
    ("trajectory", fuzz_harness::trajectory),
    ("cli_values", fuzz_harness::cli_values),
    ("stats_json", fuzz_harness::stats_json),
];

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

fn harness(target: &str) -> Harness {
    TARGETS.iter().find(|(t, _)| *t == target).expect("a fuzz target").1
}

/// The kept input `name` of `target` is rejected with a message containing each of `expected`.
fn rejected(target: &str, name: &str, expected: &[&str]) {
    let path = root().join("tests/data/fuzz").join(target).join(name);
    let data = std::fs::read(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let message = harness(target)(&data).expect_err("the input must be rejected");
    for part in expected {
        assert!(message.contains(part), "expected {part:?} in: {message}");
    }
}

#[test]
fn glb_length_shorter_than_its_header_is_refused() {
    rejected("gltf_glb", "glb-length-shorter-than-header.glb", &["fuzz.glb", "(header)", "declares 0 bytes"]);
}

#[test]
fn position_naming_a_missing_accessor_is_refused() {
    rejected(
        "gltf_json",
        "position-accessor-out-of-range.gltf",
        &["fuzz.gltf", "meshes[0].primitives[0].attributes.POSITION", "does not exist"],
    );
}

#[test]
fn position_accessor_of_the_wrong_type_is_refused() {
    rejected(
        "gltf_glb",
        "position-accessor-of-wrong-type.glb",
        &["fuzz.glb", "POSITION (accessors[", "expected Vec3 of [F32]"],
    );
}

#[test]
fn tex_coord_accessor_with_count_zero_is_refused() {
    rejected(
        "gltf_json",
        "tex-coord-accessor-count-zero.gltf",
        &["fuzz.gltf", "TEXCOORD_0 (accessors[", "count 0"],
    );
}

/// Found by reading the gltf crate's reader while fixing the two above: it reaches
/// `unreachable!()` for indices of a float type, in release builds too.
#[test]
fn indices_of_a_float_type_are_refused() {
    rejected(
        "gltf_json",
        "indices-of-float-type.gltf",
        &["fuzz.gltf", "indices (accessors[1])", "expected Scalar"],
    );
}

/// Found with the two above: positions made up of zeros (a sparse accessor without a buffer
/// view) declaring 2^40 elements made the reader allocate for all of them.
#[test]
fn implicit_positions_with_a_huge_count_are_refused_before_allocating() {
    rejected(
        "gltf_json",
        "implicit-positions-with-huge-count.gltf",
        &["fuzz.gltf", "POSITION (accessors[0])", "declares 1099511627776 elements without a bufferView"],
    );
}

/// Found by review, not by the fuzzer (which did not build a deep enough hierarchy): each of
/// 40 nodes lists the next twice as a child, so the walk would visit the last node 2^40 times.
#[test]
fn node_reached_through_two_parents_is_refused() {
    rejected(
        "gltf_json",
        "node-reached-through-two-parents.gltf",
        &["fuzz.gltf", "nodes[40]", "reached twice"],
    );
}

/// The files under `dir`, sorted (none when it does not exist).
fn files(dir: &Path) -> Vec<PathBuf> {
    let mut files: Vec<PathBuf> = match std::fs::read_dir(dir) {
        Ok(entries) => entries.map(|e| e.expect("a directory entry").path()).collect(),
        Err(_) => Vec::new(),
    };
    files.sort();
    files
}

#[test]
fn no_kept_or_corpus_input_panics() {
    let mut inputs = 0;
    for (target, run) in TARGETS {
        for dir in [root().join("tests/data/fuzz").join(target), root().join("fuzz/corpus").join(target)] {
            for path in files(&dir) {
                let data = std::fs::read(&path).unwrap();
                let outcome = std::panic::catch_unwind(|| run(&data));
                assert!(outcome.is_ok(), "{} panicked in {target}", path.display());
                inputs += 1;
            }
        }
    }
    assert!(inputs > 20, "only {inputs} inputs found");
}

#[test]
fn generated_seeds_are_accepted() {
    let seeds = [
        ("gltf_glb", "quad-textured.glb"),
        ("gltf_glb", "quad.glb"),
        ("gltf_glb", "scene-graph.glb"),
        ("gltf_glb", "sparse.glb"),
        ("gltf_json", "quad-textured.gltf"),
        ("gltf_json", "scene-graph.gltf"),
        ("gltf_json", "sparse.gltf"),
        ("gltf_json", "quad-data-uri.gltf"),
        ("trajectory", "generated-v2.traj"),
        ("trajectory", "generated-v3.traj"),
        ("scene_toml", "tiny.toml"),
        ("cli_values", "value-0"),
        ("cli_values", "value-4"),
        ("stats_json", "tiny-4-frames.json"),
        ("stats_json", "tiny-path-exact-aovs.json"),
        ("stats_json", "tiny-adaptive-stepped.json"),
    ];
    for (target, name) in seeds {
        let data = std::fs::read(root().join("fuzz/corpus").join(target).join(name)).unwrap();
        if let Err(e) = harness(target)(&data) {
            panic!("{target}/{name} is rejected: {e}");
        }
    }
    // Version 1 records no scene: it reads and replays, then has no scene to check.
    let v1 = std::fs::read(root().join("fuzz/corpus/trajectory/generated-v1.traj")).unwrap();
    assert_eq!(fuzz_harness::trajectory(&v1), Err("no recorded scene".to_string()));
}

#[test]
fn the_harness_base64_matches_the_standard() {
    assert_eq!(fuzz_harness::base64(b""), "");
    assert_eq!(fuzz_harness::base64(b"f"), "Zg==");
    assert_eq!(fuzz_harness::base64(b"fo"), "Zm8=");
    assert_eq!(fuzz_harness::base64(b"foo"), "Zm9v");
    assert_eq!(fuzz_harness::base64(b"foob"), "Zm9vYg==");
}
