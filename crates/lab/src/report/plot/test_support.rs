//! What the figure tests look for in the files they write.

use std::path::{Path, PathBuf};

/// A fresh directory under the system's temporary one.
pub(crate) fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("pushlearn-plot-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

pub(crate) fn count(path: &Path, tag: &str) -> usize {
    let text = std::fs::read_to_string(path).unwrap();
    text.matches(&format!("<{tag}")).count()
}

/// The SVG's polylines of stroke width 2: data lines and legend
/// samples (the mesh is thinner).
pub(crate) fn thick_polylines(svg: &str) -> Vec<&str> {
    svg.split("<polyline")
        .skip(1)
        .filter(|l| l.contains("stroke-width=\"2\""))
        .collect()
}

/// Points of one polyline from [`thick_polylines`].
pub(crate) fn polyline_points(line: &str) -> usize {
    line.split("points=\"").nth(1).map_or(0, |p| {
        p.split('"').next().unwrap_or("").split_whitespace().count()
    })
}

pub(crate) fn is_png(path: &Path) -> bool {
    std::fs::read(path)
        .unwrap()
        .starts_with(b"\x89PNG\r\n\x1a\n")
}
