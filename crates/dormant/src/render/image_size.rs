//! [`ImageSize`]: an image's width and height, parsed from `WIDTHxHEIGHT` and checked against
//! the limits every image obeys.

use crate::scene::limits::{image_size_problem, MAX_IMAGE_SIDE};

/// Image size as `WIDTHxHEIGHT`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ImageSize {
    pub width: u32,
    pub height: u32,
}

impl std::str::FromStr for ImageSize {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let Some((w, h)) = s.split_once(['x', 'X']) else {
            return Err(format!("'{s}': expected WIDTHxHEIGHT, e.g. 1280x720"));
        };
        let (Ok(width), Ok(height)) = (w.trim().parse::<u32>(), h.trim().parse::<u32>()) else {
            return Err(format!("'{s}': width and height must be whole numbers from 1 to {MAX_IMAGE_SIDE}"));
        };
        match image_size_problem(width, height) {
            Some(problem) => Err(problem),
            None => Ok(ImageSize { width, height }),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::ImageSize;

    #[test]
    fn size_parses_and_rejects() {
        assert_eq!("640x360".parse::<ImageSize>(), Ok(ImageSize { width: 640, height: 360 }));
        assert!("640".parse::<ImageSize>().is_err());
        assert!("0x10".parse::<ImageSize>().is_err());
        assert!("axb".parse::<ImageSize>().is_err());
        assert!("20000x10".parse::<ImageSize>().is_err());
    }
}
