//! Helpers that several schemes share, each once: the fragment word encoding ([`MdtsWord`]), the
//! post passes' sorts ([`sort`]) and the peeling schemes' layer storage and depth test.
//!
//! They sit here rather than inside the scheme that used them first, so that a scheme imports
//! only from here, the memory and the `Scheme` trait, never from another scheme.

mod layers;
#[cfg(test)]
pub(crate) mod one_pixel;
pub mod sort;
mod word;

pub(crate) use layers::{depth_test, LayerStorage};
pub use word::MdtsWord;
