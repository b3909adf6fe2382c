//! glTF metallic-roughness materials (with KHR_materials_emissive_strength) as the scene's
//! [`Material`]s, their textures loaded through the [`TextureLoader`].

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
        specular: 1.0,
        emissive: Vec3::from_array(m.emissive_factor()).max(Vec3::ZERO) * strength,
        base_color_texture: texture(pbr.base_color_texture(), "baseColorTexture"),
        metallic_roughness_texture: texture(pbr.metallic_roughness_texture(), "metallicRoughnessTexture"),
        emissive_texture: texture(m.emissive_texture(), "emissiveTexture"),
    }
}
