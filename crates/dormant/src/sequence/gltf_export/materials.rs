//! The scene's materials as glTF metallic-roughness materials that import back
//! (`scene/gltf/materials.rs`) as the identical [`Material`], and its textures as PNG images in
//! the binary buffer with their samplers' wrap modes.

use std::io::Cursor;

use serde_json::{json, Map, Value};

use super::buffer::BufferBuilder;
use super::GltfExportError;
use crate::scene::texture::{Texture, Wrap};
use crate::scene::Material;

/// The glTF arrays the materials fill.
#[derive(Default)]
pub(super) struct MaterialsJson {
    pub(super) materials: Vec<Value>,
    pub(super) textures: Vec<Value>,
    pub(super) images: Vec<Value>,
    pub(super) samplers: Vec<Value>,
    /// Whether a material needed KHR_materials_emissive_strength.
    pub(super) emissive_strength: bool,
}

/// `materials` (indices kept) and `textures` (the materials' texture indices) as glTF.
pub(super) fn materials_json(
    materials: &[Material],
    textures: &[std::sync::Arc<Texture>],
    buffer: &mut BufferBuilder,
) -> Result<MaterialsJson, GltfExportError> {
    let mut out = MaterialsJson::default();
    for (i, texture) in textures.iter().enumerate() {
        let view = buffer.view(&png(texture)?);
        out.images.push(json!({ "bufferView": view, "mimeType": "image/png", "name": texture.name }));
        out.samplers.push(json!({ "wrapS": wrap(texture.wrap_s), "wrapT": wrap(texture.wrap_t) }));
        out.textures.push(json!({ "source": i, "sampler": i }));
    }
    for (i, m) in materials.iter().enumerate() {
        let (value, strength) = material_json(i, m);
        out.emissive_strength |= strength;
        out.materials.push(value);
    }
    Ok(out)
}

/// One material; the flag says whether it uses KHR_materials_emissive_strength.
fn material_json(index: usize, m: &Material) -> (Value, bool) {
    let [r, g, b] = m.base_color.to_array();
    let mut pbr = Map::new();
    pbr.insert("baseColorFactor".into(), json!([r, g, b, 1.0f32]));
    pbr.insert("metallicFactor".into(), json!(m.metallic));
    pbr.insert("roughnessFactor".into(), json!(m.roughness));
    let texture_ref = |t: Option<u32>| t.map(|index| json!({ "index": index }));
    if let Some(t) = texture_ref(m.base_color_texture) {
        pbr.insert("baseColorTexture".into(), t);
    }
    if let Some(t) = texture_ref(m.metallic_roughness_texture) {
        pbr.insert("metallicRoughnessTexture".into(), t);
    }
    let mut value = Map::new();
    value.insert("pbrMetallicRoughness".into(), Value::Object(pbr));
    let (factor, strength) = emissive(m.emissive.to_array());
    value.insert("emissiveFactor".into(), json!(factor));
    if let Some(t) = texture_ref(m.emissive_texture) {
        value.insert("emissiveTexture".into(), t);
    }
    if let Some(s) = strength {
        value.insert(
            "extensions".into(),
            json!({ "KHR_materials_emissive_strength": { "emissiveStrength": s } }),
        );
    }
    if m.specular != 1.0 {
        tracing::warn!(
            "materials[{index}]: specular {} has no glTF metallic-roughness equivalent; \
             written as 1 with the exact value in the material's extras",
            m.specular
        );
        value.insert("extras".into(), json!({ "dormant": { "specular": m.specular } }));
    }
    (Value::Object(value), strength.is_some())
}

/// glTF's `emissiveFactor` (each component at most 1) and, when a component of `emissive` is
/// above 1, the KHR_materials_emissive_strength that multiplies it back. The strength is a
/// power of two, so that factor times strength is `emissive` bit for bit.
pub(super) fn emissive(emissive: [f32; 3]) -> ([f32; 3], Option<f32>) {
    let peak = emissive.iter().fold(0.0f32, |a, &b| a.max(b));
    if peak <= 1.0 || !peak.is_finite() {
        return (emissive, None);
    }
    let mut strength = 1.0f32;
    while strength < peak {
        strength *= 2.0;
    }
    (emissive.map(|e| e / strength), Some(strength))
}

fn wrap(w: Wrap) -> u32 {
    match w {
        Wrap::Repeat => 10497,
        Wrap::ClampToEdge => 33071,
        Wrap::MirroredRepeat => 33648,
    }
}

/// `texture`'s texels as an RGBA8 PNG.
fn png(texture: &Texture) -> Result<Vec<u8>, GltfExportError> {
    let error = |reason: String| GltfExportError::Texture { name: texture.name.clone(), reason };
    if !texture.is_consistent() {
        return Err(error(format!(
            "{} texels for {}x{}",
            texture.texels.len(),
            texture.width,
            texture.height
        )));
    }
    let raw: Vec<u8> = texture.texels.iter().flatten().copied().collect();
    let image = image::RgbaImage::from_raw(texture.width, texture.height, raw)
        .ok_or_else(|| error("texel count does not match the size".into()))?;
    let mut bytes = Cursor::new(Vec::new());
    image.write_to(&mut bytes, image::ImageFormat::Png).map_err(|e| error(e.to_string()))?;
    Ok(bytes.into_inner())
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::{emissive, material_json};
    use crate::scene::Material;

    #[test]
    fn a_specular_other_than_one_is_kept_in_the_extras() {
        let (lambertian, _) = material_json(0, &Material::lambertian(Vec3::splat(0.5)));
        assert_eq!(lambertian["extras"]["dormant"]["specular"], 0.0);
        let (diffuse, strength) = material_json(1, &Material::diffuse(Vec3::splat(0.5)));
        assert!(diffuse.get("extras").is_none() && !strength);
        let bright = Material { emissive: Vec3::new(5.0, 0.5, 0.0), ..Material::diffuse(Vec3::ZERO) };
        let (value, strength) = material_json(2, &bright);
        assert!(strength);
        assert_eq!(value["extensions"]["KHR_materials_emissive_strength"]["emissiveStrength"], 8.0);
    }

    #[test]
    fn emissive_strength_gives_back_the_exact_emission() {
        for e in [[0.5, 1.0, 0.0], [3.7, 0.1, 2.0], [1.000_001, 0.3, 0.7], [1e6, 7.0, 0.0]] {
            let (factor, strength) = emissive(e);
            assert!(factor.iter().all(|&f| f <= 1.0), "{factor:?}");
            let back = factor.map(|f| f * strength.unwrap_or(1.0));
            assert_eq!(back.map(f32::to_bits), e.map(f32::to_bits), "{e:?}");
        }
    }
}
