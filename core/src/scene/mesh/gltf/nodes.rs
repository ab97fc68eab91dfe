//! A glTF node's own transform: its matrix, or its translation, rotation and scale, held to
//! what glTF allows (a unit rotation; a matrix alone, affine, without shear) and refused
//! naming the node otherwise.

use glam::{Mat4, Quat, Vec3};

use crate::scene::asset::AssetError;

/// A node's matrix, or its translation, rotation and scale, all required to be finite.
pub(super) fn local_transform(node: &gltf::json::Node, n: usize) -> Result<Mat4, AssetError> {
    let finite = |field: &str, values: &[f32]| {
        if values.iter().all(|v| v.is_finite()) {
            Ok(())
        } else {
            Err(AssetError::gltf(
                format!("nodes[{n}].{field}"),
                "every number must be finite",
            ))
        }
    };
    if let Some(m) = &node.matrix {
        finite("matrix", m)?;
        return affine(node, n, Mat4::from_cols_array(m));
    }
    let t = node.translation.unwrap_or([0.0; 3]);
    let r = node.rotation.map_or([0.0, 0.0, 0.0, 1.0], |q| q.0);
    let s = node.scale.unwrap_or([1.0; 3]);
    finite("translation", &t)?;
    finite("rotation", &r)?;
    finite("scale", &s)?;
    Ok(Mat4::from_scale_rotation_translation(
        Vec3::from(s),
        unit(r, n)?,
        Vec3::from(t),
    ))
}

/// How far a rotation's length may be from 1: what writing a unit quaternion's four floats
/// with four decimals can cost (0.7071 twice is 0.99998), and far below a scale a user would
/// mean. glTF's rotations are unit quaternions; used as given, [0, 0, 1, 1] also stretched
/// the mesh (its x and y axes by the square root of 5).
const UNIT_SLACK: f32 = 1e-3;

/// A node's rotation `[x, y, z, w]`, made exactly unit; one that is not nearly unit is refused.
fn unit(r: [f32; 4], n: usize) -> Result<Quat, AssetError> {
    let q = Quat::from_array(r);
    let length = q.length();
    if (length - 1.0).abs() > UNIT_SLACK {
        return Err(AssetError::gltf(
            format!("nodes[{n}].rotation"),
            format!(
                "[{}] has length {}: a rotation is a unit quaternion [x, y, z, w] (length 1, \
                 within {UNIT_SLACK:e})",
                r.map(crate::text::num_text).join(", "),
                crate::text::num_text(length)
            ),
        ));
    }
    Ok(q / length)
}

/// A node's matrix as glTF allows it: alone (no translation, rotation or scale beside it),
/// with the last row [0, 0, 0, 1], and a rotation and scale without shear (its three axes at
/// right angles), so that it decomposes into translation, rotation and scale.
fn affine(node: &gltf::json::Node, n: usize, m: Mat4) -> Result<Mat4, AssetError> {
    let at = format!("nodes[{n}].matrix");
    if node.translation.is_some() || node.rotation.is_some() || node.scale.is_some() {
        return Err(AssetError::gltf(
            at,
            "a node has a matrix or translation, rotation and scale, not both",
        ));
    }
    // Exporters write the row exactly; a trace of float noise is forgiven and made exact.
    if m.row(3).distance(glam::Vec4::W) > 1e-6 {
        return Err(AssetError::gltf(
            at,
            format!(
                "its last row is [{}]: it must be [0, 0, 0, 1] (an affine transform)",
                m.row(3).to_array().map(crate::text::num_text).join(", ")
            ),
        ));
    }
    let axes = [m.x_axis, m.y_axis, m.z_axis].map(|a| a.truncate());
    for (i, j) in [(0, 1), (0, 2), (1, 2)] {
        let (a, b) = (axes[i], axes[j]);
        if a.dot(b).abs() > UNIT_SLACK * a.length() * b.length() {
            return Err(AssetError::gltf(
                at,
                format!("its columns {i} and {j} are not at right angles: a matrix must not shear"),
            ));
        }
    }
    let mut m = m;
    for column in [&mut m.x_axis, &mut m.y_axis, &mut m.z_axis] {
        column.w = 0.0;
    }
    m.w_axis.w = 1.0;
    Ok(m)
}

#[cfg(test)]
mod tests {
    use super::super::tests::edited;
    use super::super::Part;

    /// A node's transform is glTF's or refused naming the node: a rotation nearly unit (then
    /// made unit), a matrix alone, affine and without shear, and the vertices it places
    /// within the coordinates a mesh may hold.
    #[test]
    fn a_nodes_transform_is_one_gltf_allows() {
        use serde_json::json;
        let node = |edit: serde_json::Value| {
            edited(|j| {
                let n = j["nodes"][0].as_object_mut().unwrap();
                n.remove("translation");
                n.remove("scale");
                n.extend(edit.as_object().unwrap().clone());
            })
        };
        let shape = |parts: Vec<Part>| crate::scene::mesh::assemble(parts).unwrap().positions;
        let h = std::f32::consts::FRAC_1_SQRT_2;
        // Written with four decimals, a quarter turn is nearly unit: the same mesh as exact.
        let exact = shape(node(json!({ "rotation": [0.0, 0.0, h, h] })).unwrap());
        let four_decimals = (h * 1e4).round() / 1e4; // 0.7071
        let written = node(json!({ "rotation": [0.0, 0.0, four_decimals, four_decimals] }));
        let written = shape(written.unwrap());
        for (a, b) in exact.iter().zip(&written) {
            assert!(a.distance(*b) < 1e-6, "{a} {b}");
        }
        let refused = |edit: serde_json::Value, at: &str, says: &str| {
            let e = node(edit.clone()).err().unwrap().to_string();
            assert!(e.contains(at) && e.contains(says), "{edit}: {e}");
        };
        let rotation = "a rotation is a unit quaternion";
        refused(
            json!({ "rotation": [0, 0, 1, 1] }),
            "nodes[0].rotation",
            rotation,
        );
        refused(
            json!({ "rotation": [0, 0, 0, 0] }),
            "nodes[0].rotation",
            rotation,
        );
        refused(
            json!({ "rotation": [0.5, 0, 0, 0] }),
            "nodes[0].rotation",
            rotation,
        );
        let identity = [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1];
        let projective = [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 1, 0, 0, 0, 1];
        let shear = [
            1.0, 0.0, 0.0, 0.0, 0.5, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0,
        ];
        assert!(node(json!({ "matrix": identity })).is_ok());
        let noisy = [
            1.0, 0.0, 0.0, 1e-9, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0,
        ];
        let exact = shape(node(json!({ "matrix": identity })).unwrap());
        assert_eq!(
            shape(node(json!({ "matrix": noisy })).unwrap()),
            exact,
            "noise forgiven"
        );
        refused(
            json!({ "matrix": projective }),
            "nodes[0].matrix",
            "[0, 0, 0, 1]",
        );
        refused(
            json!({ "matrix": shear }),
            "nodes[0].matrix",
            "must not shear",
        );
        let both = json!({ "matrix": identity, "translation": [5, 0, 0] });
        refused(both, "nodes[0].matrix", "not both");
        let far = "past the ±1e15 a vertex coordinate may hold";
        refused(json!({ "scale": [1e30, 1e30, 1e30] }), "accessors[", far);
        refused(json!({ "translation": [1e38, 0, 0] }), "accessors[", far);
    }
}
