//! glTF metallic-roughness materials (with KHR_materials_emissive_strength and
//! KHR_materials_specular's factor) as the scene's [`Material`]s, their textures loaded
//! through the [`TextureLoader`].

use std::path::Path;

use glam::Vec3;

use super::textures::TextureLoader;
use crate::scene::Material;

pub(super) fn material(path: &Path, m: &gltf::Material, textures: &mut TextureLoader) -> Material {
    let pbr = m.pbr_metallic_roughness();
    let [r, g, b, _alpha] = pbr.base_color_factor();
    let at = |slot: &str| format!("materials[{}].{slot}", m.index().unwrap_or(0));
    let mut texture = |info: Option<gltf::texture::Info>, slot: &str| {
        let info = info?;
        if info.tex_coord() != 0 {
            tracing::warn!(
                file = %path.display(),
                "{}: uses TEXCOORD_{}; only TEXCOORD_0 is supported, using it instead",
                at(slot),
                info.tex_coord()
            );
        }
        Some(textures.get(&info.texture()))
    };
    let strength = m.emissive_strength().unwrap_or(1.0).max(0.0);
    Material {
        base_color: Vec3::new(r, g, b).max(Vec3::ZERO),
        roughness: pbr.roughness_factor().clamp(0.0, 1.0),
        metallic: pbr.metallic_factor().clamp(0.0, 1.0),
        specular: specular(path, m),
        emissive: Vec3::from_array(m.emissive_factor()).max(Vec3::ZERO) * strength,
        base_color_texture: texture(pbr.base_color_texture(), "baseColorTexture"),
        metallic_roughness_texture: texture(pbr.metallic_roughness_texture(), "metallicRoughnessTexture"),
        emissive_texture: texture(m.emissive_texture(), "emissiveTexture"),
    }
}

/// The strength of the dielectric specular layer: dormant's own export's exact value (the
/// material's `dormant` extras), else KHR_materials_specular's `specularFactor` (its colour
/// and textures are not read: a warning), else glTF's 1.
fn specular(path: &Path, m: &gltf::Material) -> f32 {
    #[derive(serde::Deserialize)]
    struct Own {
        specular: f32,
    }
    #[derive(serde::Deserialize)]
    struct Extras {
        dormant: Own,
    }
    if let Some(own) = m.extras().as_ref().and_then(|raw| serde_json::from_str::<Extras>(raw.get()).ok()) {
        return own.dormant.specular.clamp(0.0, 1.0);
    }
    let Some(s) = m.specular() else { return 1.0 };
    if s.specular_color_factor() != [1.0; 3]
        || s.specular_texture().is_some()
        || s.specular_color_texture().is_some()
    {
        tracing::warn!(
            file = %path.display(),
            "materials[{}]: KHR_materials_specular's colour and textures are not supported; only its factor is used",
            m.index().unwrap_or(0)
        );
    }
    let factor = s.specular_factor();
    if factor.is_finite() {
        factor.clamp(0.0, 1.0)
    } else {
        1.0
    }
}
