//! "Did you mean": an unknown field or variant of a scene named with the
//! nearest one its message lists (serde's "unknown field `x`, expected one
//! of `a`, `b`", and rtow's own "unknown field `x` for a metal material,
//! expected `albedo` and `fuzz`").

pub use crate::choice::nearest;

/// `message` with `, did you mean `name`?` appended when it is about an
/// unknown field or variant and one of the names it expects is similar
/// enough ([`nearest`]); else unchanged.
pub fn did_you_mean(message: &str) -> String {
    match nearest_expected(message) {
        Some(name) => format!("{message}, did you mean `{name}`?"),
        None => message.to_string(),
    }
}

/// The expected name nearest the unknown one, if similar enough.
fn nearest_expected(message: &str) -> Option<&str> {
    let (_, rest) = ["unknown field `", "unknown variant `"].iter().find_map(|p| message.split_once(p))?;
    let (unknown, rest) = rest.split_once('`')?;
    let (_, expected) = rest.split_once("expected ")?;
    let names = || expected.split('`').skip(1).step_by(2);
    // An abbreviation by initials (`spp` for `samples_per_pixel`) first.
    if let Some(name) = names().find(|n| n.contains('_') && initials(n) == unknown) {
        return Some(name);
    }
    nearest(unknown, names())
}

/// `samples_per_pixel` -> `spp`.
fn initials(name: &str) -> String {
    name.split('_').filter_map(|w| w.chars().next()).collect()
}

#[cfg(test)]
mod tests {
    use super::did_you_mean;

    #[test]
    fn the_nearest_expected_name_is_suggested() {
        assert_eq!(
            did_you_mean("unknown field `vfovv`, expected one of `look_from`, `look_at`, `vup`, `vfov_deg`"),
            "unknown field `vfovv`, expected one of `look_from`, `look_at`, `vup`, `vfov_deg`, did you mean `vfov_deg`?"
        );
        assert_eq!(
            did_you_mean("unknown variant `lambertan`, expected one of `lambertian`, `metal`"),
            "unknown variant `lambertan`, expected one of `lambertian`, `metal`, did you mean `lambertian`?"
        );
        assert!(did_you_mean("unknown field `fuz` for a metal material, expected `albedo` and `fuzz`")
            .ends_with("did you mean `fuzz`?"));
        assert!(did_you_mean("unknown field `spp`, expected one of `width`, `samples_per_pixel`")
            .ends_with("did you mean `samples_per_pixel`?"));
        // Nothing near, or not about a name: unchanged.
        for m in ["unknown field `zzz`, expected `albedo` or `fuzz`", "invalid type: string \"x\", expected a number"] {
            assert_eq!(did_you_mean(m), m);
        }
    }
}
