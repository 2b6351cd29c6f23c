//! The one font every vicpilco plot uses: DejaVu Sans embedded in the binary (assets/, Bitstream
//! Vera licence), so plotters renders text without fontconfig or system fonts.

use plotters::style::{register_font, FontStyle};
use std::sync::Once;

/// The family name the font is registered under; plotters looks text styles up by this name.
pub const FAMILY: &str = "sans-serif";

static FONT: &[u8] = include_bytes!("../assets/DejaVuSans.ttf");
static REGISTER: Once = Once::new();

/// Registers the embedded font with plotters. Cheap after the first call; call it before
/// drawing any text.
pub fn ensure_font() {
    REGISTER.call_once(|| {
        // The embedded font is a valid TTF; failure here is a build defect, reported by tests.
        let _ = register_font(FAMILY, FontStyle::Normal, FONT);
    });
}
