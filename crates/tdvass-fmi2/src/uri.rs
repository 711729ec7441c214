//! `fmuResourceLocation`: a `file:` URI of the FMU's `resources` directory.
//!
//! Accepted: `file:///path`, `file:/path`, `file://localhost/path` (scheme
//! and host case-insensitive), with percent-escapes. The FMU ships no
//! resources, so the path is only recorded and logged; it need not exist.

use std::path::PathBuf;

fn hex(b: u8) -> Option<u8> {
    match b {
        b'0'..=b'9' => Some(b - b'0'),
        b'a'..=b'f' => Some(b - b'a' + 10),
        b'A'..=b'F' => Some(b - b'A' + 10),
        _ => None,
    }
}

fn percent_decode(text: &str) -> Result<Vec<u8>, String> {
    let bytes = text.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        if bytes[i] == b'%' {
            let pair = bytes
                .get(i + 1)
                .copied()
                .and_then(hex)
                .zip(bytes.get(i + 2).copied().and_then(hex));
            match pair {
                Some((hi, lo)) => out.push(hi << 4 | lo),
                None => return Err(format!("invalid percent-escape at byte {i}")),
            }
            i += 3;
        } else {
            out.push(bytes[i]);
            i += 1;
        }
    }
    if out.contains(&0) {
        return Err("the decoded path contains a NUL byte".into());
    }
    Ok(out)
}

#[cfg(unix)]
fn to_path(bytes: Vec<u8>) -> Result<PathBuf, String> {
    use std::os::unix::ffi::OsStringExt;
    Ok(PathBuf::from(std::ffi::OsString::from_vec(bytes)))
}

#[cfg(not(unix))]
fn to_path(bytes: Vec<u8>) -> Result<PathBuf, String> {
    String::from_utf8(bytes)
        .map(PathBuf::from)
        .map_err(|_| "the decoded path is not UTF-8".to_string())
}

/// The directory a resource-location URI names. The error says what is
/// wrong with the URI.
pub fn resource_path(uri: &str) -> Result<PathBuf, String> {
    let scheme_end = uri.find(':').ok_or("not a URI (no scheme)")?;
    if !uri[..scheme_end].eq_ignore_ascii_case("file") {
        return Err(format!(
            "unsupported scheme `{}` (only file: URIs are supported)",
            &uri[..scheme_end]
        ));
    }
    let rest = &uri[scheme_end + 1..];
    if rest.contains(['?', '#']) {
        return Err("a file URI must not have a query or fragment".into());
    }
    let path = if let Some(after) = rest.strip_prefix("//") {
        let host_end = after.find('/').ok_or("no path after the authority")?;
        let host = &after[..host_end];
        if !(host.is_empty() || host.eq_ignore_ascii_case("localhost")) {
            return Err(format!("unsupported host `{host}` (only local files)"));
        }
        &after[host_end..]
    } else if rest.starts_with('/') {
        rest
    } else {
        return Err("not an absolute file URI".into());
    };
    to_path(percent_decode(path)?)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn accepted_forms() {
        for uri in [
            "file:///tmp/fmu/resources",
            "file:/tmp/fmu/resources",
            "file://localhost/tmp/fmu/resources",
            "FILE://LocalHost/tmp/fmu/resources",
            "file:///tmp/f%6Du/resources",
        ] {
            assert_eq!(
                resource_path(uri).unwrap(),
                PathBuf::from("/tmp/fmu/resources"),
                "{uri}"
            );
        }
        assert_eq!(
            resource_path("file:///tmp/a%20b%25/r").unwrap(),
            PathBuf::from("/tmp/a b%/r")
        );
        assert_eq!(resource_path("file:///").unwrap(), PathBuf::from("/"));
    }

    #[test]
    fn refused_forms() {
        for uri in [
            "",
            "/tmp/fmu",
            "http://example.com/r",
            "file://server/share/r",
            "file:relative/path",
            "file:///tmp/%zz",
            "file:///tmp/%4",
            "file:///tmp/%00x",
            "file:///tmp/a?b",
            "file://",
        ] {
            assert!(resource_path(uri).is_err(), "{uri}");
        }
    }
}
