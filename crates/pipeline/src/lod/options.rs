//! What the LOD builder is asked to build ([`LodOptions`]: the levels' triangle budgets, an error
//! limit, the lowest level's influences) and why it can refuse ([`LodError`]).

use sinew_core::MAX_INFLUENCES;

/// What to build.
#[derive(Debug, Clone, PartialEq)]
pub struct LodOptions {
    /// Triangle budget of each generated LOD as a fraction of LOD 0's triangles, decreasing.
    pub ratios: Vec<f32>,
    /// Largest simplification error allowed, relative to the mesh extent, accumulated along the
    /// chain (`None`, the default: no limit; each LOD reports the error it reached).
    pub max_error: Option<f32>,
    /// Influences per vertex kept in the lowest LOD (1 to 4).
    pub lowest_lod_influences: usize,
    /// UV seams hold even where no texture reads the UVs (a mesh to be textured later). By default
    /// they hold only on a mesh with a textured material range (docs/lod.md, "UVs no texture
    /// reads"), as gltfpack drops unused texture coordinates unless told to keep them (`-kv`).
    pub keep_uv_seams: bool,
}

impl Default for LodOptions {
    fn default() -> Self {
        Self {
            ratios: vec![0.5, 0.25],
            max_error: None,
            lowest_lod_influences: MAX_INFLUENCES,
            keep_uv_seams: false,
        }
    }
}

/// Why LODs could not be built.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum LodError {
    /// A ratio outside (0, 1].
    #[error("LOD ratio {0} is not in (0, 1]")]
    BadRatio(f32),
    /// Ratios not decreasing.
    #[error("LOD ratios must decrease: {0:?}")]
    RatiosNotDecreasing(Vec<f32>),
    /// Error limit negative or not finite.
    #[error("LOD error limit {0} must be a finite number >= 0")]
    BadMaxError(f32),
    /// Influence count outside 1..=4.
    #[error("LOD influences must be 1 to 4, not {0}")]
    BadInfluences(usize),
    /// The mesh's buffers are inconsistent.
    #[error("mesh {mesh:?}: {problem}")]
    BadMesh {
        /// Mesh name.
        mesh: String,
        /// What is wrong.
        problem: String,
    },
}

impl LodOptions {
    /// Checks the options.
    pub fn validate(&self) -> Result<(), LodError> {
        let mut prev = 1.0f32;
        for &r in &self.ratios {
            if !(r > 0.0 && r <= 1.0) {
                return Err(LodError::BadRatio(r));
            }
            if r > prev {
                return Err(LodError::RatiosNotDecreasing(self.ratios.clone()));
            }
            prev = r;
        }
        if let Some(e) = self.max_error {
            if !(e.is_finite() && e >= 0.0) {
                return Err(LodError::BadMaxError(e));
            }
        }
        if !(1..=MAX_INFLUENCES).contains(&self.lowest_lod_influences) {
            return Err(LodError::BadInfluences(self.lowest_lod_influences));
        }
        Ok(())
    }
}
