//! Range checks of command-line values, as clap value parsers: every value given on the
//! command line is checked while the arguments are parsed, whatever other options say, before
//! anything is loaded, run or written. A bad value is clap's usage error (exit 2), naming the
//! option, the value and the allowed range. The ranges are listed in docs/benchmarks.md and
//! the README.

use std::ops::RangeInclusive;

use crate::render::lookups::TraceOrder;
use crate::render::methods::Method;
use crate::scene::{Lookup, MAX_FACE_SIZE_PX, MAX_SCENE_TIME_S};

/// A whole number in `range`.
pub fn whole<T>(
    range: RangeInclusive<T>,
) -> impl Fn(&str) -> Result<T, String> + Clone + Send + Sync + 'static
where
    T: std::str::FromStr + PartialOrd + std::fmt::Display + Copy + Send + Sync + 'static,
{
    move |text: &str| {
        text.trim()
            .parse::<T>()
            .ok()
            .filter(|v| range.contains(v))
            .ok_or_else(|| {
                format!(
                    "must be a whole number in {}..={}",
                    range.start(),
                    range.end()
                )
            })
    }
}

/// A cube face size in texels (the scene format's limit, `MAX_FACE_SIZE_PX`).
pub fn face_size(text: &str) -> Result<u32, String> {
    whole(1..=MAX_FACE_SIZE_PX)(text).map_err(|_| {
        let what = match text.trim() {
            "" => "an empty entry".to_owned(),
            t => format!("`{t}`"),
        };
        format!("{what} is not a face size: a whole number in 1..={MAX_FACE_SIZE_PX}")
    })
}

/// The path of a PNG file the command writes (`compare --heatmap`, `view --screenshot`): its
/// name ends in `.png`, in any case, so that no PNG is written under another format's name
/// (`--heatmap h.exr` wrote PNG bytes that EXR readers then refused) and no folder's name
/// (`h.png/`) is taken for a file's.
pub fn png_path(text: &str) -> Result<std::path::PathBuf, String> {
    file_named(text, "png", "a PNG")
}

/// The path of an SVG file the command writes (`bench --plot`), as [`png_path`] a PNG's.
pub fn svg_path(text: &str) -> Result<std::path::PathBuf, String> {
    file_named(text, "svg", "an SVG")
}

/// `text` as the path of a file in format `format` ("a PNG"), whose name ends in `.ext` (any
/// case) and is not a folder's.
fn file_named(text: &str, ext: &str, format: &str) -> Result<std::path::PathBuf, String> {
    let path = std::path::Path::new(text);
    let named = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case(ext));
    match named && !crate::output::names_a_folder(path) {
        true => Ok(text.into()),
        false => Err(format!(
            "`{text}` is not {format} file's name: the file is {format}; name it .{ext}"
        )),
    }
}

/// A finite number in `[lo, hi]`, or `(lo, hi]` when `lo_open`; `hi` may be infinite (no
/// upper bound; the value must still be finite).
pub fn real(
    lo: f64,
    lo_open: bool,
    hi: f64,
) -> impl Fn(&str) -> Result<f64, String> + Clone + Send + Sync + 'static {
    move |text: &str| {
        let above = |v: f64| if lo_open { v > lo } else { v >= lo };
        let ok = |v: &f64| v.is_finite() && above(*v) && *v <= hi;
        text.trim()
            .parse::<f64>()
            .ok()
            .filter(ok)
            .ok_or_else(|| match (hi.is_finite(), lo_open) {
                (true, true) => format!("must be a number in ({lo}, {hi}]"),
                (true, false) => format!("must be a number in [{lo}, {hi}]"),
                (false, true) => format!("must be a finite number > {lo}"),
                (false, false) => format!("must be a finite number >= {lo}"),
            })
    }
}

/// A scene time in seconds, from 0 to [`MAX_SCENE_TIME_S`] (`--time`, `--times`).
pub fn seconds(text: &str) -> Result<f64, String> {
    real(0.0, false, MAX_SCENE_TIME_S)(text)
}

/// A registered cube fill method.
pub fn method(text: &str) -> Result<Method, String> {
    Method::parse(text.trim())
        .ok_or_else(|| format!("`{text}` is not a method: one of {}", Method::names()))
}

/// A method name or `all` (`render --method`).
pub fn method_or_all(text: &str) -> Result<String, String> {
    match text.trim() {
        "all" => Ok("all".to_owned()),
        other => method(other).map(|m| m.name().to_owned()),
    }
}

/// A mirror lookup mode.
pub fn lookup(text: &str) -> Result<Lookup, String> {
    Lookup::parse(text.trim())
        .ok_or_else(|| format!("`{text}` is not a lookup: one of {}", Lookup::names()))
}

/// A `--trace-in` value.
pub fn trace_in(text: &str) -> Result<crate::render::lookups::TraceIn, String> {
    crate::render::lookups::TraceIn::parse(text.trim())
        .ok_or_else(|| format!("`{text}` is not where to trace: fragment or compute"))
}

/// A `--bvh-layout` value.
pub fn bvh_layout(text: &str) -> Result<crate::bvh::BvhLayout, String> {
    crate::bvh::BvhLayout::parse(text.trim())
        .ok_or_else(|| format!("`{text}` is not a BVH layout: cwbvh or bvh4"))
}

/// A `--trace-order` value.
pub fn trace_order(text: &str) -> Result<TraceOrder, String> {
    TraceOrder::ALL
        .into_iter()
        .find(|o| o.name() == text.trim())
        .ok_or_else(|| format!("`{text}` is not a trace order: split or given"))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A PNG's name ends in .png, in any case; another format's, none, or a folder's is not.
    #[test]
    fn png_paths_end_in_png() {
        for good in ["h.png", "dir/H.PNG", "a.b.Png", "./x.png"] {
            assert_eq!(png_path(good), Ok(good.into()), "{good}");
        }
        for bad in [
            "h.exr",
            "h",
            "h.png/",
            "h.png/.",
            "dir/",
            ".png",
            "h.png.exr",
            "",
        ] {
            let e = png_path(bad).unwrap_err();
            assert!(e.contains("is not a PNG file's name"), "{bad}: {e}");
        }
        assert_eq!(svg_path("p.SVG"), Ok("p.SVG".into()));
        let e = svg_path("p.png").unwrap_err();
        assert!(
            e.contains("is not an SVG file's name: the file is an SVG; name it .svg"),
            "{e}"
        );
    }

    #[test]
    fn whole_numbers_are_checked_against_their_range() {
        let frames = whole(1u32..=100);
        assert_eq!(frames("1"), Ok(1));
        assert_eq!(frames("100"), Ok(100));
        for bad in ["0", "101", "", "abc", "-1", "1.5", "99999999999"] {
            assert_eq!(
                frames(bad),
                Err("must be a whole number in 1..=100".into()),
                "{bad}"
            );
        }
    }

    #[test]
    fn reals_are_finite_and_in_range() {
        let fps = real(0.0, true, 10.0);
        assert_eq!(fps("10"), Ok(10.0));
        for bad in ["0", "-3", "NaN", "inf", "10.5", "x"] {
            assert_eq!(fps(bad), Err("must be a number in (0, 10]".into()), "{bad}");
        }
        assert_eq!(real(0.0, false, 1.0)("0"), Ok(0.0));
        let unbounded = real(0.0, false, f64::INFINITY);
        assert_eq!(unbounded("1e300"), Ok(1e300));
        // A scene time stops where f64 still resolves far below a frame.
        assert_eq!(seconds("1e9"), Ok(1e9));
        assert_eq!(
            seconds("1e300"),
            Err("must be a number in [0, 1000000000]".into())
        );
        for bad in ["-1", "inf", "NaN"] {
            assert_eq!(
                unbounded(bad),
                Err("must be a finite number >= 0".into()),
                "{bad}"
            );
            assert!(seconds(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn names_list_what_is_allowed() {
        assert_eq!(face_size("64"), Ok(64));
        assert!(face_size("0")
            .unwrap_err()
            .contains("`0` is not a face size: a whole number in 1..="));
        assert!(face_size("").unwrap_err().starts_with("an empty entry"));
        assert!(method("nine-pass").unwrap_err().contains("six-pass"));
        assert_eq!(lookup("box"), Ok(Lookup::Box));
        assert!(lookup("sphere")
            .unwrap_err()
            .contains("plain, box, ray-query"));
    }
}
