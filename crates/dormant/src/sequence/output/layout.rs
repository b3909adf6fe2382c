//! [`OutputLayout`]: the files a sequence writes per frame, and their names.

use std::path::PathBuf;

use crate::render::Aov;

/// Where and in which forms a run writes its frames: `DIR/frame_NNNN.png`, with `.exr`
/// beside each PNG when `exr`, the image before denoising as `frame_NNNN.noisy.*` when
/// `keep_noisy`, and each AOV pass as `frame_NNNN.KIND.*`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct OutputLayout {
    pub dir: PathBuf,
    pub exr: bool,
    pub keep_noisy: bool,
    /// The AOV passes written, in order (a denoiser's extra guides are not written).
    pub aovs: Vec<Aov>,
}

impl OutputLayout {
    /// The files frame `index` writes, in order: the image (PNG, then EXR with `exr`), the
    /// image before denoising with `keep_noisy`, then each AOV pass the same way.
    pub fn frame_files(&self, index: u32) -> Vec<PathBuf> {
        let base = self.dir.join(format!("frame_{index:04}"));
        let mut names = vec![String::new()];
        if self.keep_noisy {
            names.push(".noisy".to_string());
        }
        names.extend(self.aovs.iter().map(|a| format!(".{}", a.name())));
        let mut files = Vec::new();
        for name in names {
            files.push(PathBuf::from(format!("{}{name}.png", base.display())));
            if self.exr {
                files.push(PathBuf::from(format!("{}{name}.exr", base.display())));
            }
        }
        files
    }

    /// Files per pass: the PNG, and the EXR with `exr`.
    pub fn files_per_pass(&self) -> usize {
        if self.exr {
            2
        } else {
            1
        }
    }
}
