//! Orthographic views for pictures: which way is up, the front and side directions, and the fit of a
//! set of points into a pixel cell.

use super::canvas::Cell;
use sinew_core::format::{Axes, Axis};
use sinew_core::glam::Vec3;

/// The model's up axis (sinew keeps the source's axes: glTF, MS3D, BVH and OBJ are Y-up, Half-Life
/// models Z-up).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Up {
    /// +Y is up; the front view looks down -Z (the model faces +Z).
    Y,
    /// +Z is up; the front view looks down -X (Half-Life models face +X).
    Z,
}

/// Which way is up and which way the model faces (unit axes, perpendicular).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Facing {
    /// Up.
    pub up: Vec3,
    /// The direction the model's front looks along.
    pub forward: Vec3,
}

impl Facing {
    /// From two axes (the caller keeps them perpendicular, as [`Axes::new`] does).
    pub fn from_axes(up: Axis, forward: Axis) -> Facing {
        Facing {
            up: Vec3::from_array(up.vector()),
            forward: Vec3::from_array(forward.vector()),
        }
    }

    /// The facing of a model's clips (`bind == false`) or of its bind pose (`bind == true`).
    pub fn of(axes: Axes, bind: bool) -> Facing {
        Facing::from_axes(
            axes.up,
            if bind {
                axes.bind_forward
            } else {
                axes.forward
            },
        )
    }
}

impl From<Up> for Facing {
    /// The convention of each up axis: Y up facing +Z (glTF), Z up facing +X (Half-Life).
    fn from(up: Up) -> Facing {
        match up {
            Up::Y => Facing::from_axes(Axis::PosY, Axis::PosZ),
            Up::Z => Facing::from_axes(Axis::PosZ, Axis::PosX),
        }
    }
}

/// A view direction: screen right, screen up, and the direction towards the viewer.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct View {
    /// Model direction drawn to the right.
    pub right: Vec3,
    /// Model direction drawn upwards.
    pub up: Vec3,
    /// Model direction pointing at the viewer (nearer points have a larger component).
    pub toward: Vec3,
}

impl View {
    /// Looking at the model's front: the viewer stands ahead of it, up is up.
    pub fn front(f: Facing) -> View {
        View {
            right: f.up.cross(f.forward),
            up: f.up,
            toward: f.forward,
        }
    }

    /// Looking at the model's side, its front pointing to the screen's right.
    pub fn side(f: Facing) -> View {
        View {
            right: f.forward,
            up: f.up,
            toward: -f.up.cross(f.forward),
        }
    }
}

/// A view fitted to a cell: model points to (pixel x, pixel y, depth), depth smaller when nearer.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Fit {
    view: View,
    scale: f32,
    cx: f32,
    cy: f32,
    px: f32,
    py: f32,
}

impl Fit {
    /// Fits `points` into `cell` with `margin` pixels on each side, centred, same scale on both axes.
    /// With no points (or a single point) the scale is 1.
    pub fn new(view: View, points: impl IntoIterator<Item = Vec3>, cell: Cell, margin: f32) -> Fit {
        let (mut lo, mut hi) = ([f32::INFINITY; 2], [f32::NEG_INFINITY; 2]);
        for p in points {
            let (x, y) = (p.dot(view.right), p.dot(view.up));
            if x.is_finite() && y.is_finite() {
                lo = [lo[0].min(x), lo[1].min(y)];
                hi = [hi[0].max(x), hi[1].max(y)];
            }
        }
        let (cx, cy, dx, dy) = if lo[0] <= hi[0] {
            (
                (lo[0] + hi[0]) * 0.5,
                (lo[1] + hi[1]) * 0.5,
                hi[0] - lo[0],
                hi[1] - lo[1],
            )
        } else {
            (0.0, 0.0, 0.0, 0.0)
        };
        let aw = (cell.w as f32 - 2.0 * margin).max(1.0);
        let ah = (cell.h as f32 - 2.0 * margin).max(1.0);
        let scale = match (dx > 0.0, dy > 0.0) {
            (true, true) => (aw / dx).min(ah / dy),
            (true, false) => aw / dx,
            (false, true) => ah / dy,
            (false, false) => 1.0,
        };
        Fit {
            view,
            scale,
            cx,
            cy,
            px: cell.x as f32 + cell.w as f32 * 0.5,
            py: cell.y as f32 + cell.h as f32 * 0.5,
        }
    }

    /// Pixel x, pixel y (downwards) and depth of a model point.
    pub fn project(&self, p: Vec3) -> Vec3 {
        Vec3::new(
            self.px + (p.dot(self.view.right) - self.cx) * self.scale,
            self.py - (p.dot(self.view.up) - self.cy) * self.scale,
            -p.dot(self.view.toward),
        )
    }

    /// The view.
    pub fn view(&self) -> View {
        self.view
    }
}

#[cfg(test)]
mod tests {
    use crate::preview::camera::*;

    #[test]
    fn fit_centres_and_scales_to_the_cell() {
        let cell = Cell {
            x: 100,
            y: 0,
            w: 200,
            h: 100,
        };
        let pts = [Vec3::new(-1.0, 0.0, 0.0), Vec3::new(1.0, 2.0, 0.0)];
        let f = Fit::new(View::front(Up::Y.into()), pts, cell, 10.0);
        // Height 2 into 80 pixels: 40 px per unit; the top point is 10 px below the cell's top.
        let top = f.project(Vec3::new(1.0, 2.0, 0.0));
        assert_eq!((top.x, top.y), (240.0, 10.0));
        let bottom = f.project(Vec3::new(-1.0, 0.0, 0.0));
        assert_eq!((bottom.x, bottom.y), (160.0, 90.0));
        assert!(
            f.project(Vec3::Z).z < f.project(Vec3::ZERO).z,
            "nearer is smaller"
        );
    }

    #[test]
    fn side_view_of_a_z_up_model_shows_its_front_to_the_right() {
        let f = Fit::new(
            View::side(Up::Z.into()),
            [Vec3::ZERO, Vec3::new(1.0, 0.0, 1.0)],
            Cell {
                x: 0,
                y: 0,
                w: 10,
                h: 10,
            },
            0.0,
        );
        assert!(f.project(Vec3::X).x > f.project(Vec3::ZERO).x);
    }

    #[test]
    fn views_from_facings_match_the_conventions() {
        // Y up facing +Z: the front view has +X to the right and +Z towards the viewer.
        let v = View::front(Up::Y.into());
        assert_eq!((v.right, v.up, v.toward), (Vec3::X, Vec3::Y, Vec3::Z));
        let v = View::side(Up::Y.into());
        assert_eq!((v.right, v.up, v.toward), (Vec3::Z, Vec3::Y, -Vec3::X));
        // Z up facing +X (Half-Life as it plays): +Y to the right, +X towards the viewer.
        let v = View::front(Up::Z.into());
        assert_eq!((v.right, v.up, v.toward), (Vec3::Y, Vec3::Z, Vec3::X));
        // A Half-Life bind pose faces -Y: the front view looks at it from -Y.
        let v = View::front(Facing::from_axes(Axis::PosZ, Axis::NegY));
        assert_eq!((v.right, v.up, v.toward), (Vec3::X, Vec3::Z, -Vec3::Y));
    }
}
