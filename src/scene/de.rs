//! Deserializers for the scene schema's numbers, vectors and sphere list, so
//! that a malformed value gets a message about what is wrong with it:
//! a vector of 4 components says so (serde's `[f32; 3]` would report
//! "trailing characters"), an integer too large says which range it must be
//! in (a JSON integer beyond u64 arrives as a float), a TOML datetime where a
//! number belongs is called a datetime (toml hands it over as a map), and the
//! sphere list stops at [`MAX_SPHERES`] while it is read (memory is bounded
//! by the limit, not by the file).

use crate::limits::{MAX_GROUPS, MAX_MEDIA, MAX_MESHES, MAX_QUADS, MAX_SAMPLED_SHAPES, MAX_SPHERES};
use serde::de::{self, Deserializer, IgnoredAny, MapAccess, SeqAccess, Unexpected, Visitor};
use std::fmt;
use std::marker::PhantomData;

/// The key toml uses for the one-entry map it hands a datetime over as.
const TOML_DATETIME: &str = "$__toml_private_datetime";

/// A map where a scalar was expected: a TOML datetime, or a real map.
fn unexpected_map<'de, A: MapAccess<'de>, E: Visitor<'de>>(mut map: A, exp: &E) -> Result<E::Value, A::Error> {
    let key: Option<String> = map.next_key()?;
    if key.as_deref() == Some(TOML_DATETIME) {
        Err(de::Error::invalid_type(Unexpected::Other("a datetime"), exp))
    } else {
        Err(de::Error::invalid_type(Unexpected::Map, exp))
    }
}

/// A number type of the schema.
trait Number: Sized + Copy {
    const EXPECTING: &'static str;
    fn from_f64(v: f64) -> Option<Self>;
    fn from_u64(v: u64) -> Option<Self>;
    fn from_i64(v: i64) -> Option<Self>;
}

impl Number for f32 {
    const EXPECTING: &'static str = "a number";
    fn from_f64(v: f64) -> Option<f32> {
        // Out-of-range values round to infinity and are refused by validation
        // ("must be finite"), with the field named. `-0.0` is read as `0.0`
        // (adding `+0.0` does exactly that and changes no other value): no
        // field gives a zero's sign a meaning, and a `-0.0` that reached the
        // kernels could take another branch than `0.0` (`-1 / -0.0 = +inf`).
        // Subnormals are kept as their value: every field that divides by
        // one is computed in f64 or refuses what it cannot represent.
        Some(v as f32 + 0.0)
    }
    fn from_u64(v: u64) -> Option<f32> {
        Some(v as f32)
    }
    fn from_i64(v: i64) -> Option<f32> {
        Some(v as f32)
    }
}

impl Number for u32 {
    const EXPECTING: &'static str = "an integer from 0 to 4294967295";
    fn from_f64(_: f64) -> Option<u32> {
        None
    }
    fn from_u64(v: u64) -> Option<u32> {
        u32::try_from(v).ok()
    }
    fn from_i64(v: i64) -> Option<u32> {
        u32::try_from(v).ok()
    }
}

impl Number for u64 {
    const EXPECTING: &'static str = "an integer from 0 to 18446744073709551615";
    fn from_f64(_: f64) -> Option<u64> {
        None
    }
    fn from_u64(v: u64) -> Option<u64> {
        Some(v)
    }
    fn from_i64(v: i64) -> Option<u64> {
        u64::try_from(v).ok()
    }
}

struct NumVisitor<T>(PhantomData<T>);

impl<'de, T: Number> Visitor<'de> for NumVisitor<T> {
    type Value = T;
    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str(T::EXPECTING)
    }
    fn visit_f64<E: de::Error>(self, v: f64) -> Result<T, E> {
        T::from_f64(v).ok_or_else(|| {
            if v.is_finite() && v.fract() == 0.0 {
                // An integer literal too large for u64 (JSON reads it as a float).
                E::invalid_value(Unexpected::Other(&format!("integer {v:e} (too large)")), &self)
            } else {
                E::invalid_type(Unexpected::Float(v), &self)
            }
        })
    }
    fn visit_u64<E: de::Error>(self, v: u64) -> Result<T, E> {
        T::from_u64(v).ok_or_else(|| E::invalid_value(Unexpected::Unsigned(v), &self))
    }
    fn visit_i64<E: de::Error>(self, v: i64) -> Result<T, E> {
        T::from_i64(v).ok_or_else(|| E::invalid_value(Unexpected::Signed(v), &self))
    }
    fn visit_map<A: MapAccess<'de>>(self, map: A) -> Result<T, A::Error> {
        unexpected_map(map, &self)
    }
}

/// A number of type `T` read with the messages above.
struct Num<T>(T);

impl<'de, T: Number> de::Deserialize<'de> for Num<T> {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        d.deserialize_any(NumVisitor(PhantomData)).map(Num)
    }
}

pub fn f32<'de, D: Deserializer<'de>>(d: D) -> Result<f32, D::Error> {
    Num::<f32>::deserialize(d).map(|n| n.0)
}

pub fn opt_f32<'de, D: Deserializer<'de>>(d: D) -> Result<Option<f32>, D::Error> {
    Option::<Num<f32>>::deserialize(d).map(|o| o.map(|n| n.0))
}

pub fn u32<'de, D: Deserializer<'de>>(d: D) -> Result<u32, D::Error> {
    Num::<u32>::deserialize(d).map(|n| n.0)
}

pub fn opt_u32<'de, D: Deserializer<'de>>(d: D) -> Result<Option<u32>, D::Error> {
    Option::<Num<u32>>::deserialize(d).map(|o| o.map(|n| n.0))
}

pub fn opt_u64<'de, D: Deserializer<'de>>(d: D) -> Result<Option<u64>, D::Error> {
    Option::<Num<u64>>::deserialize(d).map(|o| o.map(|n| n.0))
}

use de::Deserialize as _;

struct Vec3Visitor;

impl<'de> Visitor<'de> for Vec3Visitor {
    type Value = [f32; 3];
    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str("a vector of 3 numbers [x, y, z]")
    }
    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<[f32; 3], A::Error> {
        let mut v = [0.0f32; 3];
        for (i, slot) in v.iter_mut().enumerate() {
            match seq.next_element::<Num<f32>>()? {
                Some(n) => *slot = n.0,
                None => return Err(de::Error::invalid_length(i, &self)),
            }
        }
        // Count the extra components without keeping them.
        let mut n = 3usize;
        while seq.next_element::<IgnoredAny>()?.is_some() {
            n += 1;
        }
        if n > 3 {
            return Err(de::Error::invalid_length(n, &self));
        }
        Ok(v)
    }
    fn visit_map<A: MapAccess<'de>>(self, map: A) -> Result<[f32; 3], A::Error> {
        unexpected_map(map, &self)
    }
}

/// A vector with exactly 3 components; any other count is named as such.
pub fn vec3<'de, D: Deserializer<'de>>(d: D) -> Result<[f32; 3], D::Error> {
    d.deserialize_seq(Vec3Visitor)
}

struct V3(#[allow(dead_code)] [f32; 3]);

impl<'de> de::Deserialize<'de> for V3 {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        vec3(d).map(V3)
    }
}

pub fn opt_vec3<'de, D: Deserializer<'de>>(d: D) -> Result<Option<[f32; 3]>, D::Error> {
    Option::<V3>::deserialize(d).map(|o| o.map(|v| v.0))
}

/// A texture: a colour `[r, g, b]`, or a map with a `type` (see [`super::Texture`]).
struct TextureVisitor;

impl<'de> Visitor<'de> for TextureVisitor {
    type Value = super::Texture;
    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str("a colour [r, g, b] or a texture {\"type\": \"checker\" or \"noise\", ...}")
    }
    fn visit_seq<A: SeqAccess<'de>>(self, seq: A) -> Result<Self::Value, A::Error> {
        Vec3Visitor.visit_seq(seq).map(super::Texture::Solid)
    }
    fn visit_map<A: MapAccess<'de>>(self, map: A) -> Result<Self::Value, A::Error> {
        let fields = super::TextureFields::deserialize(de::value::MapAccessDeserializer::new(map))?;
        super::Texture::try_from(fields).map_err(de::Error::custom)
    }
}

pub fn texture<'de, D: Deserializer<'de>>(d: D) -> Result<super::Texture, D::Error> {
    d.deserialize_any(TextureVisitor)
}

struct Tex(super::Texture);

impl<'de> de::Deserialize<'de> for Tex {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        texture(d).map(Tex)
    }
}

pub fn opt_texture<'de, D: Deserializer<'de>>(d: D) -> Result<Option<super::Texture>, D::Error> {
    Option::<Tex>::deserialize(d).map(|o| o.map(|t| t.0))
}

/// A list refused as soon as it holds more than `max` entries (memory is
/// bounded by the limit, not by the file).
struct BoundedVisitor<T> {
    max: usize,
    what: &'static str,
    limit: &'static str,
    item: PhantomData<T>,
}

impl<'de, T: de::Deserialize<'de>> Visitor<'de> for BoundedVisitor<T> {
    type Value = Vec<T>;
    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        write!(f, "a list of at most {} {}", self.max, self.what)
    }
    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Self::Value, A::Error> {
        // The size hint comes from the input: never allocate on its word alone.
        let mut v = Vec::with_capacity(seq.size_hint().unwrap_or(0).min(4096));
        while let Some(s) = seq.next_element()? {
            if v.len() == self.max {
                return Err(de::Error::custom(format_args!(
                    "too many {}: at most {} ({})",
                    self.what, self.max, self.limit
                )));
            }
            v.push(s);
        }
        Ok(v)
    }
    fn visit_map<A: MapAccess<'de>>(self, map: A) -> Result<Self::Value, A::Error> {
        unexpected_map(map, &self)
    }
}

fn bounded<'de, D: Deserializer<'de>, T: de::Deserialize<'de>>(
    d: D,
    max: usize,
    what: &'static str,
    limit: &'static str,
) -> Result<Vec<T>, D::Error> {
    d.deserialize_seq(BoundedVisitor { max, what, limit, item: PhantomData })
}

/// The sphere list, refused as soon as it holds more than [`MAX_SPHERES`].
pub fn spheres<'de, D: Deserializer<'de>>(d: D) -> Result<Vec<super::Sphere>, D::Error> {
    bounded(d, MAX_SPHERES, "spheres", "limits::MAX_SPHERES")
}

/// The quad list, refused as soon as it holds more than [`MAX_QUADS`].
pub fn quads<'de, D: Deserializer<'de>>(d: D) -> Result<Vec<super::Quad>, D::Error> {
    bounded(d, MAX_QUADS, "quads", "limits::MAX_QUADS")
}

/// The box list: six quads each, so at most [`MAX_QUADS`] / 6 boxes.
pub fn boxes<'de, D: Deserializer<'de>>(d: D) -> Result<Vec<super::QuadBox>, D::Error> {
    bounded(d, MAX_QUADS / 6, "boxes", "limits::MAX_QUADS / 6")
}

/// The group list, refused beyond [`MAX_GROUPS`].
pub fn groups<'de, D: Deserializer<'de>>(d: D) -> Result<Vec<super::Group>, D::Error> {
    bounded(d, MAX_GROUPS, "groups", "limits::MAX_GROUPS")
}

/// A media list, refused beyond [`MAX_MEDIA`].
pub fn media<'de, D: Deserializer<'de>>(d: D) -> Result<Vec<super::Medium>, D::Error> {
    bounded(d, MAX_MEDIA, "media", "limits::MAX_MEDIA")
}

/// A mesh list, refused beyond [`MAX_MESHES`].
pub fn meshes<'de, D: Deserializer<'de>>(d: D) -> Result<Vec<super::Mesh>, D::Error> {
    bounded(d, MAX_MESHES, "meshes", "limits::MAX_MESHES")
}

/// The `sample_toward` list, refused beyond [`MAX_SAMPLED_SHAPES`].
pub fn sample_toward<'de, D: Deserializer<'de>>(d: D) -> Result<Vec<super::Shape>, D::Error> {
    bounded(d, MAX_SAMPLED_SHAPES, "sample_toward", "limits::MAX_SAMPLED_SHAPES")
}

struct BackgroundVisitor;

impl<'de> Visitor<'de> for BackgroundVisitor {
    type Value = super::Background;
    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str("\"sky\" or a colour [r, g, b]")
    }
    fn visit_str<E: de::Error>(self, v: &str) -> Result<Self::Value, E> {
        match v {
            "sky" => Ok(super::Background::Sky),
            other => Err(E::invalid_value(Unexpected::Str(other), &self)),
        }
    }
    fn visit_seq<A: SeqAccess<'de>>(self, seq: A) -> Result<Self::Value, A::Error> {
        Vec3Visitor.visit_seq(seq).map(super::Background::Constant)
    }
    fn visit_map<A: MapAccess<'de>>(self, map: A) -> Result<Self::Value, A::Error> {
        unexpected_map(map, &self)
    }
}

/// The background: `"sky"` or a colour.
pub fn background<'de, D: Deserializer<'de>>(d: D) -> Result<super::Background, D::Error> {
    d.deserialize_any(BackgroundVisitor)
}
