//! Pictures of assets, drawn on the CPU with no GPU and no window: contact sheets of a model (rest
//! pose from the front and side with its skeleton, poses across each clip, each LOD beside LOD 0) and
//! pictures of joint mappings. The same inputs give the same PNG bytes.
//!
//! - [`canvas`]: pixels, z-buffered flat and textured triangles (our own rasteriser), lines and dots
//!   (tiny-skia), PNG;
//! - [`textures`]: each material's image and how a model viewer blends it (Half-Life flags);
//! - [`text`]: labels in the embedded DejaVu Sans Mono (ab_glyph);
//! - [`camera`]: front and side orthographic views fitted to a cell;
//! - [`model`]: an asset posed through the runtime and drawn into a cell, LOD error measured;
//! - [`sheet`]: the contact sheet of `sinew preview`;
//! - [`mapping`]: the picture of a joint mapping (`sinew map --png`);
//! - [`cache`]: frames of a baked cache as written (`sinew bake --preview`).

pub mod cache;
pub mod camera;
pub mod canvas;
pub mod mapping;
pub mod model;
pub mod sheet;
pub mod text;
pub mod textures;

pub use camera::Up;
pub use sheet::{contact_sheet, SheetError, SheetOptions, SheetReport};
