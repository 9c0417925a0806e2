//! The WGSL sources, loaded in this one place from the repository's `shaders/` folder.
//!
//! `cargo xtask shaders` and this crate's tests validate them with naga.

/// Sphere occupancy on the integer lattice: entry point `raster_spheres`.
pub(crate) const RASTER_SPHERES: &str = include_str!("../../../shaders/raster_spheres.wgsl");

/// Every shader with its file name, for validation.
pub const ALL: &[(&str, &str)] = &[("raster_spheres.wgsl", RASTER_SPHERES)];

#[cfg(test)]
mod tests {
    #[test]
    fn shaders_validate_with_naga() {
        for (name, src) in super::ALL {
            let module = naga::front::wgsl::parse_str(src)
                .unwrap_or_else(|e| panic!("{}", e.emit_to_string_with_path(src, name)));
            naga::valid::Validator::new(
                naga::valid::ValidationFlags::all(),
                naga::valid::Capabilities::default(),
            )
            .validate(&module)
            .unwrap_or_else(|e| panic!("{}", e.emit_to_string_with_path(src, name)));
        }
    }
}
