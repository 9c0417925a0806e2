//! The names the evaluation and the bench give what they run.
//!
//! `mc` is marching cubes; `rfta-PRESET` is the pipeline with one of [`rfta::PRESETS`]; bare
//! `rfta` is `rfta-fast`, the setting of the shared reference results' `rfta` rows
//! (gpytoolbox's defaults), which the evaluation's tables compare it with. A name ending in
//! `-unsimplified` (`rfta-default-unsimplified`) is its mesh without simplification
//! (`rfta::Params::simplify` off), the baseline the simplification is measured against.

/// The pipeline's parameters for an `rfta` method name; `None` for another name.
pub(crate) fn rfta_params(method: &str) -> Option<rfta::Params> {
    let (method, simplify) = match method.strip_suffix("-unsimplified") {
        Some(m) => (m, false),
        None => (method, true),
    };
    let preset = match method {
        "rfta" => "fast",
        m => m.strip_prefix("rfta-")?,
    };
    let params = rfta::Params::preset(preset)?;
    Some(rfta::Params { simplify, ..params })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bare_rfta_is_the_fast_preset_and_others_name_theirs() {
        assert_eq!(rfta_params("rfta"), Some(rfta::Params::fast()));
        assert_eq!(rfta_params("rfta-fast"), Some(rfta::Params::fast()));
        assert_eq!(rfta_params("rfta-default"), Some(rfta::Params::default()));
        assert_eq!(rfta_params("rfta-paper"), Some(rfta::Params::paper_table()));
        assert_eq!(rfta_params("rfta-fastest"), None);
        let unsimplified = rfta_params("rfta-default-unsimplified").map(|p| p.simplify);
        assert_eq!(unsimplified, Some(false));
        assert_eq!(rfta_params("mc-unsimplified"), None);
        assert_eq!(rfta_params("mc"), None);
    }
}
