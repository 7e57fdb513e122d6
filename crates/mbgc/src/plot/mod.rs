//! Figures. Each figure is drawn by a function generic over the plotters backend and written as
//! SVG or PNG according to the file extension.

use std::path::{Path, PathBuf};

use crate::error::{Error, Result};

pub mod boxplot;
pub mod corner;
pub mod diagnosis;
pub mod fit_figures;
pub mod labels;
pub mod parity;
pub mod partial_dependence;
pub mod propagation;
pub mod psd;
pub mod sensitivity;

/// Font family of every text in the figures. fontconfig resolves it to DejaVu Sans, which draws
/// the Greek letters and superscripts of [`labels::axis_label`]; SVG files name the family and
/// leave the font to the viewer.
pub(crate) const FONT: &str = "sans-serif";
/// Font size of tick labels, as plotters takes it. The SVG backend writes `size / 1.24` as the
/// CSS font size, so 15 gives 12.1 px tick labels, readable at print size.
pub(crate) const TICK_FONT: u32 = 15;
/// Font size of axis descriptions (14.5 px in SVG).
pub(crate) const DESC_FONT: u32 = 18;
/// Font size of legend entries (12.1 px in SVG).
pub(crate) const LEGEND_FONT: u32 = 15;

/// Image format of a figure file, chosen by its extension.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Format {
    /// Scalable vector graphics (`.svg`), for papers and zooming.
    Svg,
    /// Raster image (`.png`), for quick viewing.
    Png,
}

/// The format `path`'s extension asks for (case-insensitive); any other extension is an error
/// naming the file.
pub fn format_of(path: &Path) -> Result<Format> {
    match path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
    {
        Some(e) if e == "svg" => Ok(Format::Svg),
        Some(e) if e == "png" => Ok(Format::Png),
        _ => Err(Error::input(
            path.display(),
            "file extension",
            "expected .svg or .png for a figure",
        )),
    }
}

/// Creates the parent directory of a figure file.
pub fn prepare(path: &Path) -> Result<Format> {
    let f = format_of(path)?;
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
    }
    Ok(f)
}

pub(crate) fn draw_error(path: &Path, e: impl std::fmt::Display) -> Error {
    Error::invalid(format!("{}: cannot draw the figure: {e}", path.display()))
}

/// Where a figure is drawn before it replaces `path`: a hidden file in the same folder with the
/// same extension (the bitmap backend picks its format by it). Drawing there and renaming means a
/// figure never writes through another name of an existing file (a hard link to an input) and
/// never leaves half a figure behind.
pub fn temp_path(path: &Path) -> PathBuf {
    let name = path.file_name().unwrap_or_default().to_string_lossy();
    path.with_file_name(format!(
        ".{name}.{}.tmp.{}",
        std::process::id(),
        match format_of(path) {
            Ok(Format::Png) => "png",
            _ => "svg",
        }
    ))
}

/// Moves a drawn figure from its temporary file onto `path`, or removes the temporary file when
/// drawing failed.
pub fn finish(path: &Path, tmp: &Path, drawn: Result<()>) -> Result<()> {
    match drawn {
        Ok(()) => std::fs::rename(tmp, path).map_err(|e| {
            let _ = std::fs::remove_file(tmp);
            Error::io(path, e)
        }),
        Err(e) => {
            let _ = std::fs::remove_file(tmp);
            Err(e)
        }
    }
}

/// Draws a figure with whichever backend the file extension asks for. `$draw` is a generic
/// function taking the root drawing area as its first argument. The file appears whole, by a
/// rename ([`temp_path`]).
#[macro_export]
macro_rules! draw_figure {
    ($path:expr, $size:expr, $draw:ident ( $($arg:expr),* )) => {{
        use plotters::prelude::*;
        let path: &std::path::Path = $path;
        let format = $crate::plot::prepare(path)?;
        let tmp = $crate::plot::temp_path(path);
        let drawn = match format {
            $crate::plot::Format::Svg => {
                let root = SVGBackend::new(&tmp, $size).into_drawing_area();
                $draw(&root, $($arg),*).and_then(|_| root.present())
                    .map_err(|e| $crate::plot::draw_error(path, e))
            }
            $crate::plot::Format::Png => {
                let root = BitMapBackend::new(&tmp, $size).into_drawing_area();
                $draw(&root, $($arg),*).and_then(|_| root.present())
                    .map_err(|e| $crate::plot::draw_error(path, e))
            }
        };
        $crate::plot::finish(path, &tmp, drawn)
    }};
}

/// Test helpers shared by the figure modules.
#[cfg(test)]
pub(crate) mod test_util {
    /// The CSS font sizes (px) of all text elements of an SVG file written by plotters.
    pub fn font_sizes(svg: &str) -> Vec<f64> {
        svg.split("font-size=\"")
            .skip(1)
            .map(|rest| {
                let v = rest.split('"').next().unwrap_or("");
                v.parse::<f64>()
                    .unwrap_or_else(|e| panic!("font-size \"{v}\": {e}"))
            })
            .collect()
    }

    /// Asserts that the SVG has text and that all of it is at least `min` px high.
    pub fn assert_fonts_at_least(svg: &str, min: f64) {
        let sizes = font_sizes(svg);
        assert!(!sizes.is_empty(), "no text in the figure");
        let small: Vec<f64> = sizes.iter().copied().filter(|&s| s < min).collect();
        assert!(small.is_empty(), "text smaller than {min} px: {small:?}");
    }

    #[test]
    fn font_sizes_are_read() {
        let svg = r#"<text font-size="12.096774" x="1">a</text><text font-size="9.67">b</text>"#;
        assert_eq!(font_sizes(svg), vec![12.096774, 9.67]);
        assert!(std::panic::catch_unwind(|| assert_fonts_at_least(svg, 12.0)).is_err());
        assert_fonts_at_least(svg, 9.0);
    }
}
