//! The `.sinew` reader. Layout: docs/format.md. Every count is checked against the bytes that remain
//! before anything is allocated; all arithmetic on values from the file is checked.

mod clips;
mod container;
mod cursor;
mod game;
mod sections;

pub use container::{read, sections};
