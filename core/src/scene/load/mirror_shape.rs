//! `mirror.shape` and the fields each shape reads, from the shapes' registry
//! (`crate::mirror`): every field a shape names is required and checked against its unit; a
//! field only another shape reads is refused, so a scene never carries a number that does
//! nothing; a key no shape reads is an unknown field.

use super::numbers::Range;
use super::{Ctx, R};
use crate::mirror::{self, FieldUnit, MirrorShape, ShapeKind};
use crate::scene::error::SceneError;
use crate::scene::format::{MirrorSpec, MIRROR_KEYS};

impl Ctx<'_> {
    pub(super) fn mirror_shape(&self, spec: &MirrorSpec) -> R<MirrorShape> {
        let kind = match spec.shape.as_deref() {
            None => mirror::kind("sphere").expect("the sphere is registered"),
            Some(name) => mirror::kind(name).ok_or_else(|| {
                self.invalid(
                    "mirror.shape",
                    format!("unknown mirror shape \"{name}\" (known: {})", shape_names()),
                )
            })?,
        };
        let reads: Vec<String> = kind
            .fields
            .iter()
            .map(|f| format!("mirror.{}", f.name))
            .collect();
        for (key, _) in &spec.shape_fields {
            let field = format!("mirror.{key}");
            if !mirror::is_shape_field(key) {
                return Err(self.unknown_mirror_field(key));
            }
            if !reads.contains(&field) {
                let why = format!("a {} mirror reads only {}", kind.name, reads.join(", "));
                return Err(self.unused(&field, &why));
            }
        }
        let mut values = Vec::with_capacity(kind.fields.len());
        for f in kind.fields {
            let field = format!("mirror.{}", f.name);
            let value = spec.shape_fields.iter().find(|(k, _)| k == f.name);
            let Some((_, value)) = value else {
                let why = format!("a {} mirror needs it", kind.name);
                return Err(self.missing(&field, &why));
            };
            let v = self.shape_number(&field, value)?;
            match f.unit {
                // Finite, and positive in single precision too.
                FieldUnit::Metres => self.positive(&field, v)?,
                FieldUnit::Degrees { above, below } => {
                    self.ranged(&field, v, Range::open(above as f32, below as f32))?
                }
            };
            values.push(v);
        }
        (kind.build)(&values).map_err(|e| self.invalid(&format!("mirror.{}", e.field), e.message))
    }

    /// A shape's field's value: a number (an integer reads as one).
    fn shape_number(&self, field: &str, value: &toml::Value) -> R<f64> {
        match value {
            toml::Value::Float(v) => Ok(*v),
            toml::Value::Integer(v) => Ok(*v as f64),
            other => Err(SceneError::WrongType {
                location: self.loc.location(field),
                field: field.to_string(),
                message: format!("invalid type: {}, expected a number", other.type_str()),
            }),
        }
    }

    /// A key of `[mirror]` that neither the table nor any shape reads (a typo, most often).
    fn unknown_mirror_field(&self, key: &str) -> SceneError {
        let field = format!("mirror.{key}");
        let mut shape_fields: Vec<&str> = mirror::kinds()
            .flat_map(|k: &ShapeKind| k.fields.iter().map(|f| f.name))
            .collect();
        shape_fields.sort_unstable();
        shape_fields.dedup();
        let quoted = |names: &[&str]| {
            let q: Vec<String> = names.iter().map(|n| format!("`{n}`")).collect();
            q.join(", ")
        };
        SceneError::UnknownField {
            location: self.loc.location(&field),
            message: format!(
                "unknown field `{key}`, expected one of {}, or a shape's field ({})",
                quoted(&MIRROR_KEYS),
                quoted(&shape_fields)
            ),
            field,
        }
    }
}

/// The registered shapes' names, comma-separated.
fn shape_names() -> String {
    let names: Vec<&str> = mirror::kinds().map(|k| k.name).collect();
    names.join(", ")
}
