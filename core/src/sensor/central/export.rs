//! The models in the tools' own file formats, and readers for them (for our tests, and for
//! anyone who wants a file back as numbers):
//!
//! - `opencv_omnidir.yaml`: cv::FileStorage YAML with `K` (3x3), `xi` (1x1), `D` (1x4) as
//!   `!!opencv-matrix` nodes and `image_width` / `image_height`, what `cv2.FileStorage(...)
//!   .getNode("K").mat()` reads and `cv2.omnidir.projectPoints` takes;
//! - `kalibr_camchain.yaml`: Kalibr's camchain layout for one camera (`camera_model: omni`,
//!   `intrinsics: [xi, fu, fv, pu, pv]`, `distortion_model: radtan`, `distortion_coeffs`,
//!   `resolution: [width, height]`);
//! - `ocamcalib_calib_results.txt`: OCamCalib's export, the layout its C `get_ocam_model`
//!   reads: comment lines, then `ss` (count first), `invpol` (count first), the centre as row
//!   and column, the affine c d e, and the image height and width.
//!
//! Numbers are written with 17 significant digits and a signed exponent (`1.2345e+02`), which
//! reads back to the same f64 and which YAML 1.1 (PyYAML, used by Kalibr) takes as a float.

use super::{MeiModel, OcamModel};

/// A file that is not what the writer here writes.
#[derive(Debug, thiserror::Error)]
#[error("{0}")]
pub struct ParseError(String);

/// A float with 17 significant digits and a signed exponent.
pub fn number(v: f64) -> String {
    let text = format!("{v:.16e}");
    match text.split_once('e') {
        Some((mantissa, exp)) if !exp.starts_with('-') => format!("{mantissa}e+{exp:0>2}"),
        Some((mantissa, exp)) => format!("{mantissa}e-{:0>2}", &exp[1..]),
        None => text,
    }
}

fn list(values: &[f64]) -> String {
    values
        .iter()
        .map(|v| number(*v))
        .collect::<Vec<_>>()
        .join(", ")
}

fn opencv_matrix(name: &str, rows: usize, cols: usize, data: &[f64]) -> String {
    format!(
        "{name}: !!opencv-matrix\n   rows: {rows}\n   cols: {cols}\n   dt: d\n   data: [ {} ]\n",
        list(data)
    )
}

/// `opencv_omnidir.yaml`.
pub fn opencv_yaml(m: &MeiModel, width: u32, height: u32) -> String {
    let k = [m.fx, m.skew, m.cx, 0.0, m.fy, m.cy, 0.0, 0.0, 1.0];
    format!(
        "%YAML:1.0\n---\n# Mei's unified model for cv::omnidir, fitted by specchio to the exact ray map.\n\
         # Frame: x = sensor right, y = sensor down, z = towards the camera (docs/sensor-models.md).\n\
         {}{}{}image_width: {width}\nimage_height: {height}\n",
        opencv_matrix("K", 3, 3, &k),
        opencv_matrix("xi", 1, 1, &[m.xi]),
        opencv_matrix("D", 1, 4, &[m.k1, m.k2, m.p1, m.p2]),
    )
}

/// `kalibr_camchain.yaml` (Kalibr has no skew: the model must have none), naming `rostopic`
/// as the camera's image topic: the one a specchio bag holds its images on
/// (`sensor::bag::kalibr_image_topic`), which Kalibr's tools read the images from.
pub fn kalibr_yaml(m: &MeiModel, width: u32, height: u32, rostopic: &str) -> String {
    assert_eq!(
        m.skew, 0.0,
        "Kalibr's omni model has no skew; fits here fix it at 0"
    );
    format!(
        "# Kalibr camchain: Mei's unified model (omni) with radtan distortion, fitted by specchio.\n\
         cam0:\n  camera_model: omni\n  intrinsics: [{}]\n  distortion_model: radtan\n  \
         distortion_coeffs: [{}]\n  resolution: [{width}, {height}]\n  cam_overlaps: []\n  \
         rostopic: {rostopic}\n",
        list(&[m.xi, m.fx, m.fy, m.cx, m.cy]),
        list(&[m.k1, m.k2, m.p1, m.p2]),
    )
}

/// `ocamcalib_calib_results.txt`.
pub fn ocamcalib_txt(m: &OcamModel) -> String {
    let counted = |v: &[f64]| {
        let values: Vec<String> = v.iter().map(|x| number(*x)).collect();
        format!("{} {}", v.len(), values.join(" "))
    };
    format!(
        "#polynomial coefficients for the DIRECT mapping function (ocam_model.ss in MATLAB). These are used by cam2world\n\n{}\n\n\
         #polynomial coefficients for the inverse mapping function (ocam_model.invpol in MATLAB). These are used by world2cam\n\n{}\n\n\
         #center: \"row\" and \"column\", starting from 0 (C convention)\n\n{} {}\n\n\
         #affine parameters \"c\", \"d\", \"e\"\n\n{} {} {}\n\n\
         #image size: \"height\" and \"width\"\n\n{} {}\n",
        counted(&m.ss),
        counted(&m.invpol),
        number(m.xc),
        number(m.yc),
        number(m.c),
        number(m.d),
        number(m.e),
        m.height,
        m.width
    )
}

/// The numbers in `[a, b, ...]` on the line that holds `key` (after `after`, the line where
/// a node starts, if given).
fn bracketed(text: &str, key: &str, after: Option<&str>) -> Result<Vec<f64>, ParseError> {
    let start = match after {
        Some(node) => text
            .find(node)
            .ok_or_else(|| ParseError(format!("no `{node}` node")))?,
        None => 0,
    };
    let line = text[start..]
        .lines()
        .find(|l| l.trim_start().starts_with(key))
        .ok_or_else(|| ParseError(format!("no `{key}` line")))?;
    let inner = line
        .split_once('[')
        .and_then(|(_, r)| r.split_once(']'))
        .map(|(inner, _)| inner)
        .ok_or_else(|| ParseError(format!("`{key}` has no [list]")))?;
    inner
        .split(',')
        .filter(|s| !s.trim().is_empty())
        .map(|s| {
            s.trim()
                .parse()
                .map_err(|_| ParseError(format!("`{key}`: {s:?} is not a number")))
        })
        .collect()
}

fn scalar(text: &str, key: &str) -> Result<u32, ParseError> {
    text.lines()
        .find_map(|l| l.strip_prefix(key))
        .and_then(|r| r.trim().parse().ok())
        .ok_or_else(|| ParseError(format!("no whole number `{key}`")))
}

fn exactly<const N: usize>(v: Vec<f64>, what: &str) -> Result<[f64; N], ParseError> {
    v.try_into()
        .map_err(|v: Vec<f64>| ParseError(format!("`{what}` has {} values, not {N}", v.len())))
}

/// Reads [`opencv_yaml`]'s file: the model and the image (width, height).
pub fn read_opencv_yaml(text: &str) -> Result<(MeiModel, [u32; 2]), ParseError> {
    let k: [f64; 9] = exactly(bracketed(text, "data:", Some("K:"))?, "K")?;
    let [xi] = exactly(bracketed(text, "data:", Some("xi:"))?, "xi")?;
    let [k1, k2, p1, p2] = exactly(bracketed(text, "data:", Some("D:"))?, "D")?;
    let model = MeiModel {
        fx: k[0],
        skew: k[1],
        cx: k[2],
        fy: k[4],
        cy: k[5],
        xi,
        k1,
        k2,
        p1,
        p2,
    };
    let size = [
        scalar(text, "image_width:")?,
        scalar(text, "image_height:")?,
    ];
    Ok((model, size))
}

/// Reads [`kalibr_yaml`]'s file: the model and the resolution (width, height).
pub fn read_kalibr_yaml(text: &str) -> Result<(MeiModel, [u32; 2]), ParseError> {
    for key in ["camera_model: omni", "distortion_model: radtan"] {
        if !text.lines().any(|l| l.trim() == key) {
            return Err(ParseError(format!("no `{key}`")));
        }
    }
    let [xi, fx, fy, cx, cy] = exactly(bracketed(text, "intrinsics:", None)?, "intrinsics")?;
    let [k1, k2, p1, p2] = exactly(
        bracketed(text, "distortion_coeffs:", None)?,
        "distortion_coeffs",
    )?;
    let [w, h] = exactly(bracketed(text, "resolution:", None)?, "resolution")?;
    let model = MeiModel {
        fx,
        fy,
        skew: 0.0,
        cx,
        cy,
        xi,
        k1,
        k2,
        p1,
        p2,
    };
    Ok((model, [w as u32, h as u32]))
}

/// Reads a `calib_results.txt` as OCamCalib's `get_ocam_model` does: the five blocks of
/// numbers between the comment lines.
pub fn read_ocamcalib_txt(text: &str) -> Result<OcamModel, ParseError> {
    let blocks: Vec<Vec<f64>> = text
        .lines()
        .map(str::trim)
        .filter(|l| !l.is_empty() && !l.starts_with('#'))
        .map(|l| {
            l.split_whitespace()
                .map(|v| {
                    v.parse()
                        .map_err(|_| ParseError(format!("{v:?} is not a number")))
                })
                .collect()
        })
        .collect::<Result<_, _>>()?;
    let [pol, invpol, centre, affine, size] = exactly_blocks(blocks)?;
    let counted = |v: Vec<f64>, what: &str| match v.split_first() {
        Some((n, rest)) if *n as usize == rest.len() => Ok(rest.to_vec()),
        _ => Err(ParseError(format!(
            "`{what}`: the count does not match the values"
        ))),
    };
    let [xc, yc] = exactly(centre, "center")?;
    let [c, d, e] = exactly(affine, "affine")?;
    let [height, width] = exactly(size, "image size")?;
    Ok(OcamModel {
        ss: counted(pol, "ss")?,
        invpol: counted(invpol, "invpol")?,
        xc,
        yc,
        c,
        d,
        e,
        height: height as u32,
        width: width as u32,
    })
}

fn exactly_blocks(blocks: Vec<Vec<f64>>) -> Result<[Vec<f64>; 5], ParseError> {
    let n = blocks.len();
    blocks
        .try_into()
        .map_err(|_| ParseError(format!("{n} blocks of numbers, not 5")))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_have_a_signed_exponent_and_read_back_exactly() {
        assert_eq!(number(250.5), "2.5050000000000000e+02");
        assert_eq!(number(-0.00125), "-1.2500000000000000e-03");
        for v in [std::f64::consts::PI, -1.0 / 3.0, 1e-300, 0.0, 123456.789] {
            assert_eq!(number(v).parse::<f64>().unwrap(), v);
        }
    }
}
