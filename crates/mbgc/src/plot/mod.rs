//! Figures. Each figure is drawn by a function generic over the plotters backend and written as
//! SVG or PNG according to the file extension.

use std::path::Path;

use crate::error::{Error, Result};

pub mod boxplot;
pub mod corner;
pub mod diagnosis;
pub mod fit_figures;
pub mod labels;
pub mod parity;
pub mod psd;
pub mod sensitivity;

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

/// Draws a figure with whichever backend the file extension asks for. `$draw` is a generic
/// function taking the root drawing area as its first argument.
#[macro_export]
macro_rules! draw_figure {
    ($path:expr, $size:expr, $draw:ident ( $($arg:expr),* )) => {{
        use plotters::prelude::*;
        let path: &std::path::Path = $path;
        match $crate::plot::prepare(path)? {
            $crate::plot::Format::Svg => {
                let root = SVGBackend::new(path, $size).into_drawing_area();
                $draw(&root, $($arg),*).and_then(|_| root.present())
                    .map_err(|e| $crate::plot::draw_error(path, e))
            }
            $crate::plot::Format::Png => {
                let root = BitMapBackend::new(path, $size).into_drawing_area();
                $draw(&root, $($arg),*).and_then(|_| root.present())
                    .map_err(|e| $crate::plot::draw_error(path, e))
            }
        }
    }};
}
