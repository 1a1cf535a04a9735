//! Service: access control at the edge of the routes (before any handler). `ashlar serve
//! --tokens FILE` turns it on: every `/v1/…` request must then carry `Authorization: Bearer
//! TOKEN` with a token of the file, or is answered 401 (problem+json). The page, its assets,
//! `/healthz` and `/openapi.yaml` stay open. Tokens are kept only as SHA-256 digests.
use sha2::{Digest, Sha256};
use std::path::Path;

/// What a token may do. Every role may use the whole API for now (jobs are not yet owned by the
/// token that submitted them); `admin` is parsed so that token files need not change when
/// ownership arrives.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Role {
    User,
    Admin,
}

/// The accepted tokens, as digests.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Tokens {
    entries: Vec<([u8; 32], Role)>,
}

/// SHA-256 of a token.
pub fn digest(token: &str) -> [u8; 32] {
    let d = Sha256::digest(token.as_bytes());
    let mut out = [0u8; 32];
    out.copy_from_slice(&d);
    out
}

fn hex32(s: &str) -> Option<[u8; 32]> {
    if s.len() != 64 {
        return None;
    }
    let mut out = [0u8; 32];
    for (i, o) in out.iter_mut().enumerate() {
        *o = u8::from_str_radix(s.get(2 * i..2 * i + 2)?, 16).ok()?;
    }
    Some(out)
}

impl Tokens {
    /// One token a line: `ROLE TOKEN`, ROLE `user` or `admin`, TOKEN either the token itself
    /// (at least 16 characters; hashed when read) or `sha256:HEX`, its digest (so that the
    /// file need not hold the secret). Blank lines and `#` comments are skipped.
    pub fn parse(text: &str) -> Result<Self, String> {
        let mut entries = Vec::new();
        for (n, line) in text.lines().enumerate() {
            let line = line.trim();
            if line.is_empty() || line.starts_with('#') {
                continue;
            }
            let mut parts = line.split_whitespace();
            let (Some(role), Some(token), None) = (parts.next(), parts.next(), parts.next()) else {
                return Err(format!(
                    "line {}: expected `ROLE TOKEN` (ROLE user or admin)",
                    n + 1
                ));
            };
            let role = match role {
                "user" => Role::User,
                "admin" => Role::Admin,
                other => {
                    return Err(format!(
                        "line {}: role {other:?} is not user or admin",
                        n + 1
                    ))
                }
            };
            let d = match token.strip_prefix("sha256:") {
                Some(h) => hex32(&h.to_ascii_lowercase()).ok_or_else(|| {
                    format!("line {}: sha256: must be followed by 64 hex digits", n + 1)
                })?,
                None if token.chars().count() >= 16 => digest(token),
                None => {
                    return Err(format!(
                        "line {}: a token must have at least 16 characters",
                        n + 1
                    ))
                }
            };
            entries.push((d, role));
        }
        if entries.is_empty() {
            return Err("no token in the file".into());
        }
        Ok(Self { entries })
    }

    pub fn load(path: &Path) -> Result<Self, String> {
        let text = std::fs::read_to_string(path)
            .map_err(|e| format!("--tokens {}: {e}", path.display()))?;
        Self::parse(&text).map_err(|e| format!("--tokens {}: {e}", path.display()))
    }

    /// The role of a presented token; every entry is compared in full, in constant time, so
    /// the answer's timing does not say how close a guess was.
    pub fn check(&self, presented: &str) -> Option<Role> {
        let d = digest(presented);
        let mut found = None;
        for (e, role) in &self.entries {
            let diff = e.iter().zip(&d).fold(0u8, |acc, (a, b)| acc | (a ^ b));
            if diff == 0 {
                found = Some(*role);
            }
        }
        found
    }
}

/// The bearer token of an `Authorization` header value.
pub fn bearer(value: &str) -> Option<&str> {
    let (scheme, token) = value.trim().split_once(' ')?;
    scheme
        .eq_ignore_ascii_case("bearer")
        .then(|| token.trim())
        .filter(|t| !t.is_empty())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tokens_are_kept_hashed_and_checked() {
        let hashed: String = digest("another-secret-token-2")
            .iter()
            .map(|b| format!("{b:02x}"))
            .collect();
        let t = Tokens::parse(&format!(
            "# comment\nuser a-long-enough-token-1\n\nadmin sha256:{hashed}\n"
        ))
        .expect("valid");
        assert_eq!(t.check("a-long-enough-token-1"), Some(Role::User));
        assert_eq!(t.check("another-secret-token-2"), Some(Role::Admin));
        assert_eq!(t.check("a-long-enough-token-2"), None);
        assert!(Tokens::parse("user short").is_err());
        assert!(Tokens::parse("root a-long-enough-token-1").is_err());
        assert!(Tokens::parse("").is_err());
        assert_eq!(bearer("Bearer abc"), Some("abc"));
        assert_eq!(bearer("bearer  abc "), Some("abc"));
        assert_eq!(bearer("Basic abc"), None);
    }
}
