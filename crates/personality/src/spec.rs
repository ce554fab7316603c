//! `PROFILE:NODE` (`akd:1`) as every host of drives takes it (`drivebus
//! serve --drive`, the Python package), with the messages users see.

use crate::Profile;

/// Parses `PROFILE:NODE` with a decimal node-ID 1..=127; the error says
/// which part is wrong and lists the profiles.
pub fn drive_spec(spec: &str) -> Result<(Profile, u8), String> {
    let names = || Profile::all().iter().map(|p| p.name()).collect::<Vec<_>>().join(", ");
    let Some((p, n)) = spec.split_once(':') else {
        return Err(format!("bad drive `{spec}`: expected PROFILE:NODE, e.g. akd:1 (profiles: {})", names()));
    };
    let Some(profile) = Profile::from_name(p) else {
        return Err(format!("bad drive `{spec}`: unknown profile `{p}` (profiles: {})", names()));
    };
    match n.trim().parse::<u32>() {
        Ok(v @ 1..=127) => Ok((profile, v as u8)),
        _ => Err(format!("bad drive `{spec}`: node-ID `{n}` is not in 1..127")),
    }
}

/// Parses every spec ([`drive_spec`]) and refuses two drives with one
/// node-ID.
pub fn drive_specs<S: AsRef<str>>(specs: &[S]) -> Result<Vec<(Profile, u8)>, String> {
    let mut out: Vec<(Profile, u8)> = Vec::new();
    for s in specs {
        let s = s.as_ref();
        let (profile, node) = drive_spec(s)?;
        if let Some((p, n)) = out.iter().find(|o| o.1 == node) {
            return Err(format!("bad drive `{s}`: node-ID {node} is already taken by {p}:{n}"));
        }
        out.push((profile, node));
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn specs_and_their_messages() {
        assert_eq!(drive_spec("akd:1"), Ok((Profile::Akd, 1)));
        assert_eq!(drive_spec("SSD-630:127").map(|s| s.0), Ok(Profile::Ssd630));
        assert_eq!(drive_spec("akd:0").unwrap_err(), "bad drive `akd:0`: node-ID `0` is not in 1..127");
        assert!(
            drive_spec("x:1")
                .unwrap_err()
                .starts_with("bad drive `x:1`: unknown profile `x` (profiles: kc1, akd")
        );
        assert!(drive_spec("akd").unwrap_err().contains("expected PROFILE:NODE"));
        let two = ["akd:1", "kc1:1"];
        assert_eq!(drive_specs(&two).unwrap_err(), "bad drive `kc1:1`: node-ID 1 is already taken by akd:1");
        assert_eq!(drive_specs(&["akd:1", "dds6:2"]), Ok(vec![(Profile::Akd, 1), (Profile::Dds6, 2)]));
    }
}
