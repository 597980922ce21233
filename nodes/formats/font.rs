//! The font charts are drawn with, shipped so that no system font is needed.

const FONT: &[u8] = include_bytes!("../../assets/fonts/DejaVuSans.ttf");

/// Registers the shipped DejaVu Sans as plotters' "sans-serif" (once), so charts and the
/// `plot` node draw text without depending on the system's fonts.
pub fn register_plot_font() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        // The font is shipped with the crate, so this cannot fail for a valid build.
        let _ =
            plotters::style::register_font("sans-serif", plotters::style::FontStyle::Normal, FONT);
    });
}
