//! Custom serde deserialisers for the scene types: [`RotationSpec`] (axis/angle or 3×3 matrix,
//! the base rotation R_y(−π/2) of paper Sect. 2.1), [`InertiaSpec`] (diagonal or full I_i of
//! eq. 22a, I_b of eq. 25), and the helpers behind `deserialize_with` for 3-vectors
//! (`exact3`, `opt_exact3`, whose entries may be angles such as `"pi/2"`) and optional
//! angles in radians (`opt_angle_radians`).

use serde::Deserialize;

use super::{Angle, InertiaSpec, RotationSpec};

impl<'de> Deserialize<'de> for RotationSpec {
    fn deserialize<D: serde::Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> serde::de::Visitor<'de> for V {
            type Value = RotationSpec;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str(
                    "a rotation: { axis = \"x\"|\"y\"|\"z\", angle = ... } or a 3x3 matrix \
                     [[r11, r12, r13], [r21, r22, r23], [r31, r32, r33]]",
                )
            }
            fn visit_map<A: serde::de::MapAccess<'de>>(
                self,
                mut map: A,
            ) -> Result<RotationSpec, A::Error> {
                const FIELDS: &[&str] = &["axis", "angle"];
                let mut axis: Option<String> = None;
                let mut angle: Option<Angle> = None;
                while let Some(key) = map.next_key::<String>()? {
                    match key.as_str() {
                        "axis" if axis.is_none() => axis = Some(map.next_value()?),
                        "angle" if angle.is_none() => angle = Some(map.next_value()?),
                        "axis" | "angle" => {
                            return Err(serde::de::Error::custom(format!(
                                "duplicate field `{key}`"
                            )));
                        }
                        other => return Err(serde::de::Error::unknown_field(other, FIELDS)),
                    }
                }
                Ok(RotationSpec::Axis {
                    axis: axis.ok_or_else(|| serde::de::Error::missing_field("axis"))?,
                    angle: angle.ok_or_else(|| serde::de::Error::missing_field("angle"))?,
                })
            }
            fn visit_seq<A: serde::de::SeqAccess<'de>>(
                self,
                mut seq: A,
            ) -> Result<RotationSpec, A::Error> {
                let mut m = [[0.0; 3]; 3];
                for (i, row) in m.iter_mut().enumerate() {
                    *row = seq
                        .next_element::<V3>()?
                        .ok_or_else(|| serde::de::Error::invalid_length(i, &"3 rows"))?
                        .0;
                }
                if seq.next_element::<serde::de::IgnoredAny>()?.is_some() {
                    return Err(serde::de::Error::invalid_length(4, &"3 rows"));
                }
                Ok(RotationSpec::Matrix(m))
            }
        }
        deserializer.deserialize_any(V)
    }
}

/// A 3-vector that, unlike `[f64; 3]` with the toml deserializer, rejects extra elements.
struct V3([f64; 3]);

impl<'de> Deserialize<'de> for V3 {
    fn deserialize<D: serde::Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> serde::de::Visitor<'de> for V {
            type Value = V3;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("an array of 3 numbers")
            }
            fn visit_seq<A: serde::de::SeqAccess<'de>>(self, mut seq: A) -> Result<V3, A::Error> {
                let mut v = [0.0; 3];
                let mut n = 0;
                while let Some(x) = seq.next_element::<f64>()? {
                    if n < 3 {
                        v[n] = x;
                    }
                    n += 1;
                }
                if n == 3 {
                    Ok(V3(v))
                } else {
                    Err(serde::de::Error::invalid_length(n, &self))
                }
            }
        }
        deserializer.deserialize_seq(V)
    }
}

pub(super) fn exact3<'de, D: serde::Deserializer<'de>>(d: D) -> Result<[f64; 3], D::Error> {
    V3::deserialize(d).map(|v| v.0)
}

pub(super) fn opt_exact3<'de, D: serde::Deserializer<'de>>(
    d: D,
) -> Result<Option<[f64; 3]>, D::Error> {
    Option::<V3>::deserialize(d).map(|v| v.map(|v| v.0))
}

pub(super) fn opt_angle_radians<'de, D: serde::Deserializer<'de>>(
    d: D,
) -> Result<Option<f64>, D::Error> {
    Option::<Angle>::deserialize(d).map(|a| a.map(|a| a.radians()))
}

/// One element of an inertia array: a number (diagonal form) or a row (full form).
enum NumOrRow {
    Num(f64),
    Row(Vec<f64>),
}

impl<'de> Deserialize<'de> for NumOrRow {
    fn deserialize<D: serde::Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> serde::de::Visitor<'de> for V {
            type Value = NumOrRow;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("a number or a row of 3 numbers")
            }
            fn visit_f64<E: serde::de::Error>(self, v: f64) -> Result<NumOrRow, E> {
                Ok(NumOrRow::Num(v))
            }
            fn visit_i64<E: serde::de::Error>(self, v: i64) -> Result<NumOrRow, E> {
                Ok(NumOrRow::Num(v as f64))
            }
            fn visit_u64<E: serde::de::Error>(self, v: u64) -> Result<NumOrRow, E> {
                Ok(NumOrRow::Num(v as f64))
            }
            fn visit_seq<A: serde::de::SeqAccess<'de>>(
                self,
                mut seq: A,
            ) -> Result<NumOrRow, A::Error> {
                let mut row = Vec::new();
                while let Some(x) = seq.next_element::<f64>()? {
                    row.push(x);
                }
                Ok(NumOrRow::Row(row))
            }
        }
        deserializer.deserialize_any(V)
    }
}

impl<'de> Deserialize<'de> for InertiaSpec {
    fn deserialize<D: serde::Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> serde::de::Visitor<'de> for V {
            type Value = InertiaSpec;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str(
                    "an inertia: [Ixx, Iyy, Izz] or a 3x3 matrix [[Ixx, Ixy, Ixz], [Ixy, Iyy, \
                     Iyz], [Ixz, Iyz, Izz]] (kg m^2)",
                )
            }
            fn visit_seq<A: serde::de::SeqAccess<'de>>(
                self,
                mut seq: A,
            ) -> Result<InertiaSpec, A::Error> {
                let mut items = Vec::new();
                while let Some(x) = seq.next_element::<NumOrRow>()? {
                    items.push(x);
                }
                let shape_err = || {
                    serde::de::Error::custom(
                        "inertia must be [Ixx, Iyy, Izz] or a 3x3 matrix [[..], [..], [..]]",
                    )
                };
                if items.len() != 3 {
                    return Err(shape_err());
                }
                match (&items[0], &items[1], &items[2]) {
                    (NumOrRow::Num(a), NumOrRow::Num(b), NumOrRow::Num(c)) => {
                        Ok(InertiaSpec::Diagonal([*a, *b, *c]))
                    }
                    (NumOrRow::Row(a), NumOrRow::Row(b), NumOrRow::Row(c))
                        if a.len() == 3 && b.len() == 3 && c.len() == 3 =>
                    {
                        Ok(InertiaSpec::Full([
                            [a[0], a[1], a[2]],
                            [b[0], b[1], b[2]],
                            [c[0], c[1], c[2]],
                        ]))
                    }
                    _ => Err(shape_err()),
                }
            }
        }
        deserializer.deserialize_any(V)
    }
}
