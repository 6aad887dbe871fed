//! What a technique and the renderer agree on, as plain data: a technique's parameters ([`params`]), the
//! overlay primitives it draws ([`overlay`]) and the hardware-independent work it counts ([`work`]). The
//! renderer's services draw and count them, the techniques fill them and the app shows them; the trait itself
//! is `Technique` (`technique/mod.rs`, which re-exports these modules under `technique::`). Imports only the
//! ground floor.

pub mod overlay;
pub mod params;
pub mod work;
