//! The textures materials use, decoded once each to RGBA8 with their samplers' wrap modes;
//! an image that cannot be loaded is a warning and a magenta texture.

use std::collections::BTreeMap;

use super::Source;
use crate::scene::texture::{Texture, Wrap};

/// Decodes the textures materials use, each glTF texture once (and each image once).
pub(super) struct TextureLoader<'a> {
    source: &'a Source<'a>,
    document: &'a gltf::Document,
    buffers: &'a [gltf::buffer::Data],
    /// glTF texture index -> index in `textures`.
    by_texture: BTreeMap<usize, u32>,
    images: BTreeMap<usize, Texture>,
    textures: Vec<Texture>,
}

impl<'a> TextureLoader<'a> {
    pub(super) fn new(
        source: &'a Source<'a>,
        document: &'a gltf::Document,
        buffers: &'a [gltf::buffer::Data],
    ) -> Self {
        Self {
            source,
            document,
            buffers,
            by_texture: BTreeMap::new(),
            images: BTreeMap::new(),
            textures: Vec::new(),
        }
    }

    /// The decoded textures, in the order [`Self::get`] numbered them.
    pub(super) fn into_textures(self) -> Vec<Texture> {
        self.textures
    }

    pub(super) fn get(&mut self, texture: &gltf::Texture) -> u32 {
        if let Some(&i) = self.by_texture.get(&texture.index()) {
            return i;
        }
        let image = texture.source();
        let decoded = self.images.entry(image.index()).or_insert_with(|| {
            let name = format!("{}: images[{}]", self.source.name.display(), image.index());
            decode_image(self.source, self.document, self.buffers, &image).unwrap_or_else(|why| {
                tracing::warn!("{name}: {why}; using a magenta texture");
                Texture::magenta(&name)
            })
        });
        let sampler = texture.sampler();
        let wrap = |w: gltf::texture::WrappingMode| match w {
            gltf::texture::WrappingMode::Repeat => Wrap::Repeat,
            gltf::texture::WrappingMode::ClampToEdge => Wrap::ClampToEdge,
            gltf::texture::WrappingMode::MirroredRepeat => Wrap::MirroredRepeat,
        };
        let texture_data =
            Texture { wrap_s: wrap(sampler.wrap_s()), wrap_t: wrap(sampler.wrap_t()), ..decoded.clone() };
        let i = self.textures.len() as u32;
        self.textures.push(texture_data);
        self.by_texture.insert(texture.index(), i);
        i
    }
}

/// The encoded bytes of an image (buffer view, data URI or file next to the glTF), decoded by
/// whatever format the bytes are in (PNG and JPEG are compiled in).
pub(super) fn decode_image(
    source: &Source,
    document: &gltf::Document,
    buffers: &[gltf::buffer::Data],
    image: &gltf::Image,
) -> Result<Texture, String> {
    let json = &document.as_json().images[image.index()];
    let bytes: Vec<u8> = match (&json.buffer_view, &json.uri) {
        (Some(view), _) => {
            let view = document.views().nth(view.value()).ok_or("buffer view does not exist")?;
            let data = buffers.get(view.buffer().index()).ok_or("buffer does not exist")?;
            let end = view.offset().checked_add(view.length()).ok_or("buffer view is too long")?;
            data.0.get(view.offset()..end).ok_or("buffer view lies outside its buffer")?.to_vec()
        }
        (None, Some(uri)) => {
            gltf::buffer::Data::from_source(gltf::buffer::Source::Uri(uri), source.base)
                .map_err(|e| format!("cannot read '{uri}': {e}"))?
                .0
        }
        (None, None) => return Err("has neither a uri nor a bufferView".into()),
    };
    let decoded = image::load_from_memory(&bytes).map_err(|e| format!("cannot decode: {e}"))?.to_rgba8();
    let (width, height) = decoded.dimensions();
    if width == 0 || height == 0 {
        return Err(format!("image is {width}x{height}"));
    }
    Ok(Texture {
        name: format!("{}: images[{}]", source.name.display(), image.index()),
        width,
        height,
        texels: decoded.pixels().map(|p| p.0).collect(),
        wrap_s: Wrap::Repeat,
        wrap_t: Wrap::Repeat,
    })
}
