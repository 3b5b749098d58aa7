//! Textures of a picture: each material's image decoded to RGBA, how a model viewer draws it (opaque,
//! masked, additive; Half-Life's texture flags), and nearest-texel sampling.

use sinew_core::format::game::material_flags;
use sinew_core::format::Asset;
use sinew_scene::Image;
use std::collections::BTreeMap;

/// How a texture's pixels combine with the picture.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Blend {
    /// Every texel covers what is behind it.
    Opaque,
    /// Texels with alpha below 128 are holes (Half-Life's masked textures: palette index 255).
    Masked,
    /// Texels are added to what is behind them and hide nothing (Half-Life's additive textures).
    Additive,
}

/// One material's texture.
#[derive(Debug, Clone, PartialEq)]
pub struct Texture {
    /// Width in texels.
    pub width: u32,
    /// Height in texels.
    pub height: u32,
    /// `width * height` RGBA texels, rows from the top.
    pub rgba: Vec<u8>,
    /// How it is drawn.
    pub blend: Blend,
    /// A Half-Life chrome texture: environment-mapped in the game, drawn here plainly in its mean
    /// colour (its stored coordinates are not meant for it).
    pub chrome: bool,
    /// The mean colour of its opaque texels.
    pub mean: [u8; 3],
}

impl Texture {
    /// The texel at texture coordinates `(u, v)` (sinew's convention: origin top left, v down),
    /// repeating outside 0..1, nearest texel.
    pub fn sample(&self, u: f32, v: f32) -> [u8; 4] {
        let wrap = |x: f32, n: u32| -> usize {
            let t = (x - x.floor()) * n as f32;
            if t.is_finite() {
                (t as usize).min(n as usize - 1)
            } else {
                0
            }
        };
        let (x, y) = (wrap(u, self.width), wrap(v, self.height));
        let i = (y * self.width as usize + x) * 4;
        [
            self.rgba[i],
            self.rgba[i + 1],
            self.rgba[i + 2],
            self.rgba[i + 3],
        ]
    }
}

/// The textures of an asset's materials, by material name.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Textures {
    by_material: BTreeMap<String, Texture>,
}

impl Textures {
    /// Matches `images` (named as materials' `texture` strings name them) to the asset's materials.
    /// The blend mode comes from the material's Half-Life flags (`GAME` section): additive, masked;
    /// otherwise an image with transparent texels is masked. Images whose size does not match their
    /// bytes are skipped.
    pub fn new(asset: &Asset, images: &[Image]) -> Textures {
        let mut by_material = BTreeMap::new();
        for m in &asset.materials {
            let Some(key) = &m.texture else { continue };
            let Some(img) = images.iter().find(|i| &i.name == key) else {
                continue;
            };
            let n = (img.width as usize).checked_mul(img.height as usize);
            if img.width == 0 || n.and_then(|n| n.checked_mul(4)) != Some(img.rgba.len()) {
                continue;
            }
            let flags = asset
                .game
                .material_flags
                .iter()
                .find(|f| f.material == m.name)
                .map_or(0, |f| f.flags);
            let holes = img.rgba.chunks_exact(4).any(|p| p[3] < 128);
            let blend = if flags & material_flags::ADDITIVE != 0 {
                Blend::Additive
            } else if flags & material_flags::MASKED != 0 || holes {
                Blend::Masked
            } else {
                Blend::Opaque
            };
            let (mut sum, mut count) = ([0u64; 3], 0u64);
            for p in img.rgba.chunks_exact(4).filter(|p| p[3] >= 128) {
                for k in 0..3 {
                    sum[k] += u64::from(p[k]);
                }
                count += 1;
            }
            let mean = sum.map(|s| (s / count.max(1)) as u8);
            by_material.insert(
                m.name.clone(),
                Texture {
                    width: img.width,
                    height: img.height,
                    rgba: img.rgba.clone(),
                    blend,
                    chrome: flags & material_flags::CHROME != 0,
                    mean,
                },
            );
        }
        Textures { by_material }
    }

    /// The texture of material `name`.
    pub fn get(&self, name: &str) -> Option<&Texture> {
        self.by_material.get(name)
    }

    /// True when no material has a texture.
    pub fn is_empty(&self) -> bool {
        self.by_material.is_empty()
    }

    /// How many materials have a texture.
    pub fn len(&self) -> usize {
        self.by_material.len()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use sinew_core::format::game::MaterialFlags;
    use sinew_core::format::Material;

    fn image(name: &str, rgba: Vec<u8>, w: u32) -> Image {
        Image {
            name: name.into(),
            width: w,
            height: (rgba.len() / 4) as u32 / w,
            rgba,
        }
    }

    #[test]
    fn flags_and_alpha_choose_the_blend() {
        let mut asset = Asset::default();
        for (m, t) in [
            ("a", "a.bmp"),
            ("b", "b.bmp"),
            ("c", "c.bmp"),
            ("d", "missing"),
        ] {
            asset.materials.push(Material {
                name: m.into(),
                base_color: [1.0; 4],
                texture: Some(t.into()),
            });
        }
        asset.game.material_flags = vec![
            MaterialFlags {
                material: "b".into(),
                flags: material_flags::ADDITIVE,
            },
            MaterialFlags {
                material: "c".into(),
                flags: material_flags::CHROME,
            },
        ];
        let opaque = vec![10, 20, 30, 255, 30, 40, 50, 255];
        let holed = vec![10, 20, 30, 255, 0, 0, 0, 0];
        let t = Textures::new(
            &asset,
            &[
                image("a.bmp", holed, 2),
                image("b.bmp", opaque.clone(), 2),
                image("c.bmp", opaque, 1),
            ],
        );
        assert_eq!(t.len(), 3);
        assert_eq!(t.get("a").unwrap().blend, Blend::Masked);
        assert_eq!(t.get("a").unwrap().mean, [10, 20, 30]);
        assert_eq!(t.get("b").unwrap().blend, Blend::Additive);
        assert_eq!(t.get("b").unwrap().mean, [20, 30, 40]);
        assert!(t.get("c").unwrap().chrome);
        assert!(t.get("d").is_none());
    }

    #[test]
    fn sampling_is_nearest_and_repeats() {
        let t = Texture {
            width: 2,
            height: 2,
            rgba: (0..16).collect(),
            blend: Blend::Opaque,
            chrome: false,
            mean: [0; 3],
        };
        assert_eq!(t.sample(0.1, 0.1), [0, 1, 2, 3]);
        assert_eq!(t.sample(0.9, 0.1), [4, 5, 6, 7]);
        assert_eq!(t.sample(0.1, 0.9), [8, 9, 10, 11]);
        assert_eq!(t.sample(1.9, -0.1), [12, 13, 14, 15]);
        assert_eq!(t.sample(f32::NAN, 0.0), [0, 1, 2, 3]);
    }
}
