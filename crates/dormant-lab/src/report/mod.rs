//! The lab's reports: `dormant bench paper` (`paper.json`, `paper.md`, one figure per
//! workload) and `dormant bench regimes` (`regimes.md`, `regimes.png`), the JSON form every
//! benchmark report takes, and the plotting helpers every figure (the binary's `report.png`
//! too) is drawn with.

mod paper;
mod paper_plot;
pub mod plot;
mod regimes;

pub use paper::write_paper;
pub use regimes::write_regimes;

/// `report` as JSON with `simd_path`, the BVH SIMD path that ran (`DORMANT_SIMD`): every
/// benchmark report carries it, whether printed by `--json` or written as a file.
pub fn bench_json(report: &impl serde::Serialize) -> serde_json::Value {
    let mut value = serde_json::to_value(report).expect("bench reports serialise");
    if let Some(map) = value.as_object_mut() {
        map.insert("simd_path".into(), serde_json::json!(dormant::accel::bvh::SimdPath::current()));
    }
    value
}

/// Failures writing a report or a figure.
#[derive(Debug, thiserror::Error)]
pub enum ReportError {
    #[error("cannot write {path}: {source}")]
    Write { path: std::path::PathBuf, source: std::io::Error },
    #[error("cannot read {path}: {source}")]
    Read { path: std::path::PathBuf, source: std::io::Error },
    #[error("cannot draw {path}: {message}")]
    Plot { path: std::path::PathBuf, message: String },
}
