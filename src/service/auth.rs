//! Service: access control at the edge of the routes (before any handler). `ashlar serve
//! --tokens FILE` turns it on: every `/v1/…` request must then carry `Authorization: Bearer
//! TOKEN` with a token of the file, or is answered 401 (problem+json). The page, its assets,
//! `/healthz` and `/openapi.yaml` stay open. Tokens are kept only as SHA-256 digests.
use sha2::{Digest, Sha256};
use std::path::Path;

/// What a token may do: a `user` lists, reads, cancels and deletes only the jobs and searches
/// it submitted (another token's answer 404, so that ids do not leak); an `admin` sees and
/// manages every one.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Role {
    User,
    Admin,
}

/// Who made a request: the role of its token and the token's owner id.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Identity {
    pub role: Role,
    /// A stable id of the token ([`owner_id`]), recorded as the owner of what it submits.
    pub owner: String,
}

/// The owner id of a token, from its digest: 16 hex digits of SHA-256 over a fixed label and
/// the digest. Stable across restarts and token-file rewrites (a `sha256:` line gives the same
/// id as the token itself), and neither the token nor its digest can be read back from it.
pub fn owner_id(digest: &[u8; 32]) -> String {
    let mut h = Sha256::new();
    h.update(b"ashlar-owner\0");
    h.update(digest);
    h.finalize()[..8]
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect()
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

/// What is wrong in a `--tokens` file's text (the line, 1-based).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum TokensError {
    #[error("line {line}: expected `ROLE TOKEN` (ROLE user or admin)")]
    Form { line: usize },
    #[error("line {line}: role {role:?} is not user or admin")]
    Role { line: usize, role: String },
    #[error("line {line}: sha256: must be followed by 64 hex digits")]
    Digest { line: usize },
    #[error("line {line}: a token must have at least 16 characters")]
    Short { line: usize },
    #[error("no token in the file")]
    Empty,
}

/// `--tokens FILE` unreadable or malformed (the file, then the cause).
#[derive(Debug, thiserror::Error)]
pub enum TokensFileError {
    #[error("--tokens {}: {source}", path.display())]
    Read {
        path: std::path::PathBuf,
        source: std::io::Error,
    },
    #[error("--tokens {}: {source}", path.display())]
    Parse {
        path: std::path::PathBuf,
        source: TokensError,
    },
}

/// A signing key too short to be safe (bytes after trimming whitespace; 32 needed).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SigningKeyError {
    #[error("the signing key has {bytes} bytes; give at least 32 (e.g. `head -c 32 /dev/urandom | base64`)")]
    Short { bytes: usize },
}

/// `--signing-key-file FILE` unreadable or too short (the file, then the cause).
#[derive(Debug, thiserror::Error)]
pub enum SigningKeyFileError {
    #[error("--signing-key-file {}: {source}", path.display())]
    Read {
        path: std::path::PathBuf,
        source: std::io::Error,
    },
    #[error("--signing-key-file {}: {source}", path.display())]
    Key {
        path: std::path::PathBuf,
        source: SigningKeyError,
    },
}

impl Tokens {
    /// One token a line: `ROLE TOKEN`, ROLE `user` or `admin`, TOKEN either the token itself
    /// (at least 16 characters; hashed when read) or `sha256:HEX`, its digest (so that the
    /// file need not hold the secret). Blank lines and `#` comments are skipped.
    pub fn parse(text: &str) -> Result<Self, TokensError> {
        let mut entries = Vec::new();
        for (n, line) in text.lines().enumerate() {
            let line = line.trim();
            if line.is_empty() || line.starts_with('#') {
                continue;
            }
            let mut parts = line.split_whitespace();
            let (Some(role), Some(token), None) = (parts.next(), parts.next(), parts.next()) else {
                return Err(TokensError::Form { line: n + 1 });
            };
            let role = match role {
                "user" => Role::User,
                "admin" => Role::Admin,
                other => {
                    return Err(TokensError::Role {
                        line: n + 1,
                        role: other.to_string(),
                    })
                }
            };
            let d = match token.strip_prefix("sha256:") {
                Some(h) => {
                    hex32(&h.to_ascii_lowercase()).ok_or(TokensError::Digest { line: n + 1 })?
                }
                None if token.chars().count() >= 16 => digest(token),
                None => return Err(TokensError::Short { line: n + 1 }),
            };
            entries.push((d, role));
        }
        if entries.is_empty() {
            return Err(TokensError::Empty);
        }
        Ok(Self { entries })
    }

    pub fn load(path: &Path) -> Result<Self, TokensFileError> {
        let path_buf = || path.to_path_buf();
        let text = std::fs::read_to_string(path).map_err(|source| TokensFileError::Read {
            path: path_buf(),
            source,
        })?;
        Self::parse(&text).map_err(|source| TokensFileError::Parse {
            path: path_buf(),
            source,
        })
    }

    /// The role of a presented token; every entry is compared in full, in constant time, so
    /// the answer's timing does not say how close a guess was.
    pub fn check(&self, presented: &str) -> Option<Role> {
        self.identify(presented).map(|i| i.role)
    }

    /// The identity of a presented token (see [`Tokens::check`]).
    pub fn identify(&self, presented: &str) -> Option<Identity> {
        let d = digest(presented);
        let mut found = None;
        for (e, role) in &self.entries {
            let diff = e.iter().zip(&d).fold(0u8, |acc, (a, b)| acc | (a ^ b));
            if diff == 0 {
                found = Some(*role);
            }
        }
        found.map(|role| Identity {
            role,
            owner: owner_id(&d),
        })
    }
}

/// How a request was let in, put in its extensions by the access check of the routes.
#[derive(Debug, Clone, PartialEq)]
pub enum Access {
    /// The server runs without tokens: everything is open, as without ownership.
    Open,
    /// A bearer token.
    Token(Identity),
    /// A valid signed URL (`?expires=&sig=`) of this exact path, issued to whoever could read
    /// the job when the link was made.
    Signed,
}

impl Access {
    /// May this caller see (read, cancel, delete) a job owned by `owner`? Others' jobs answer
    /// 404, as if they did not exist.
    pub fn may_see(&self, owner: Option<&str>) -> bool {
        match self {
            Access::Open | Access::Signed => true,
            Access::Token(i) => i.role == Role::Admin || owner == Some(i.owner.as_str()),
        }
    }

    /// Whose jobs a listing shows: `None` everyone's (no tokens, or an admin).
    pub fn list_filter(&self) -> Option<&str> {
        match self {
            Access::Token(i) if i.role == Role::User => Some(&i.owner),
            _ => None,
        }
    }

    /// The owner recorded on what this caller submits.
    pub fn owner(&self) -> Option<String> {
        match self {
            Access::Token(i) => Some(i.owner.clone()),
            _ => None,
        }
    }
}

impl<S: Send + Sync> axum::extract::FromRequestParts<S> for Access {
    type Rejection = std::convert::Infallible;

    async fn from_request_parts(
        parts: &mut axum::http::request::Parts,
        _state: &S,
    ) -> Result<Self, Self::Rejection> {
        // The access check runs before every handler and always leaves one; a router built
        // without it has no tokens either.
        Ok(parts
            .extensions
            .get::<Access>()
            .cloned()
            .unwrap_or(Access::Open))
    }
}

/// The key of signed URLs (`?expires=UNIX&sig=HEX`): links a browser or Foxglove opens without
/// an `Authorization` header (artifact downloads, event streams). `sig` is HMAC-SHA256 of
/// `GET\n{path}\n{expires}` under this key; it covers the path (so the job) and the expiry, not
/// other query parameters (a signed histories link still takes `?format=`, `?every=`).
#[derive(Clone)]
pub struct SigningKey {
    key: Vec<u8>,
    /// How long a URL signed now stays valid.
    pub validity: std::time::Duration,
}

impl std::fmt::Debug for SigningKey {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SigningKey")
            .field("validity", &self.validity)
            .finish_non_exhaustive()
    }
}

impl PartialEq for SigningKey {
    fn eq(&self, other: &Self) -> bool {
        self.key == other.key && self.validity == other.validity
    }
}

/// Why a signed URL is refused (answered 401).
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum SignError {
    #[error("the signed link has expired; reload the job to get a fresh one")]
    Expired,
    #[error("the link's signature does not match (altered, or signed by another server start)")]
    BadSignature,
    #[error("a signed link needs both ?expires=UNIX and ?sig=HEX")]
    Malformed,
}

type HmacSha256 = hmac::Hmac<Sha256>;

/// Default validity of a signed URL: long enough to start a download or open Foxglove after
/// loading the job, short enough that a leaked link soon stops working.
pub const SIGNED_URL_SECONDS: u64 = 900;

impl SigningKey {
    /// A key from `--signing-key-file` (its bytes, surrounding whitespace trimmed; at least
    /// 32 bytes so that it cannot be guessed).
    pub fn from_bytes(key: &[u8], validity: std::time::Duration) -> Result<Self, SigningKeyError> {
        let key = key.trim_ascii();
        if key.len() < 32 {
            return Err(SigningKeyError::Short { bytes: key.len() });
        }
        Ok(Self {
            key: key.to_vec(),
            validity,
        })
    }

    pub fn load(path: &Path, validity: std::time::Duration) -> Result<Self, SigningKeyFileError> {
        let bytes = std::fs::read(path).map_err(|source| SigningKeyFileError::Read {
            path: path.to_path_buf(),
            source,
        })?;
        Self::from_bytes(&bytes, validity).map_err(|source| SigningKeyFileError::Key {
            path: path.to_path_buf(),
            source,
        })
    }

    /// A fresh random key (256 bits from the OS's generator, through two v4 UUIDs: 244 random
    /// bits): links signed before a restart stop working after it.
    pub fn random(validity: std::time::Duration) -> Self {
        let mut key = Vec::with_capacity(32);
        key.extend_from_slice(uuid::Uuid::new_v4().as_bytes());
        key.extend_from_slice(uuid::Uuid::new_v4().as_bytes());
        Self { key, validity }
    }

    fn mac(&self, path: &str, expires: u64) -> HmacSha256 {
        use hmac::{KeyInit, Mac};
        // HMAC takes keys of any length; this cannot fail.
        let mut m = <HmacSha256 as KeyInit>::new_from_slice(&self.key)
            .unwrap_or_else(|_| unreachable!("HMAC accepts every key length"));
        m.update(format!("GET\n{path}\n{expires}").as_bytes());
        m
    }

    /// `path?expires=…&sig=…`, valid for [`SigningKey::validity`] from `now` (Unix seconds).
    pub fn sign(&self, path: &str, now: u64) -> String {
        use hmac::Mac;
        let expires = now + self.validity.as_secs();
        let sig: String = self
            .mac(path, expires)
            .finalize()
            .into_bytes()
            .iter()
            .map(|b| format!("{b:02x}"))
            .collect();
        format!("{path}?expires={expires}&sig={sig}")
    }

    /// Check a signature of `path` (constant-time comparison).
    pub fn verify(
        &self,
        path: &str,
        expires: Option<&str>,
        sig: Option<&str>,
        now: u64,
    ) -> Result<(), SignError> {
        use hmac::Mac;
        let (Some(expires), Some(sig)) = (expires, sig) else {
            return Err(SignError::Malformed);
        };
        let expires: u64 = expires.parse().map_err(|_| SignError::Malformed)?;
        let sig = hex32(&sig.to_ascii_lowercase()).ok_or(SignError::BadSignature)?;
        self.mac(path, expires)
            .verify_slice(&sig)
            .map_err(|_| SignError::BadSignature)?;
        if expires < now {
            return Err(SignError::Expired);
        }
        Ok(())
    }
}

/// Unix seconds now.
pub fn unix_now() -> u64 {
    std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map(|d| d.as_secs())
        .unwrap_or(0)
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
        // The owner id is the same whether the file holds the token or its digest, differs
        // between tokens, and is not the digest.
        let a = t.identify("another-secret-token-2").expect("admin");
        assert_eq!(a.owner, owner_id(&digest("another-secret-token-2")));
        assert_eq!(a.owner.len(), 16);
        assert!(!hashed.contains(&a.owner));
        let u = t.identify("a-long-enough-token-1").expect("user");
        assert_ne!(u.owner, a.owner);
        assert!(Tokens::parse("user short").is_err());
        assert!(Tokens::parse("root a-long-enough-token-1").is_err());
        assert!(Tokens::parse("").is_err());
        assert_eq!(bearer("Bearer abc"), Some("abc"));
        assert_eq!(bearer("bearer  abc "), Some("abc"));
        assert_eq!(bearer("Basic abc"), None);
    }

    #[test]
    fn signed_urls_hold_for_their_path_until_they_expire() {
        let key = SigningKey::random(std::time::Duration::from_secs(900));
        let url = key.sign("/v1/jobs/abc/events", 1_000);
        let (path, q) = url.split_once('?').expect("query");
        let get = |k: &str| {
            q.split('&')
                .find_map(|kv| kv.strip_prefix(&format!("{k}=")))
                .map(str::to_string)
        };
        let (e, s) = (get("expires"), get("sig"));
        assert_eq!(e.as_deref(), Some("1900"));
        let ok = |p: &str, e: Option<&str>, s: Option<&str>, now| key.verify(p, e, s, now);
        assert_eq!(ok(path, e.as_deref(), s.as_deref(), 1_500), Ok(()));
        assert_eq!(ok(path, e.as_deref(), s.as_deref(), 1_900), Ok(()));
        assert_eq!(
            ok(path, e.as_deref(), s.as_deref(), 1_901),
            Err(SignError::Expired)
        );
        // Another path, a later expiry, a flipped digit, another key: refused.
        assert_eq!(
            ok("/v1/jobs/abd/events", e.as_deref(), s.as_deref(), 1_500),
            Err(SignError::BadSignature)
        );
        assert_eq!(
            ok(path, Some("99999"), s.as_deref(), 1_500),
            Err(SignError::BadSignature)
        );
        let mut bad = s.clone().expect("sig");
        let c = if bad.starts_with('0') { "1" } else { "0" };
        bad.replace_range(0..1, c);
        assert_eq!(
            ok(path, e.as_deref(), Some(&bad), 1_500),
            Err(SignError::BadSignature)
        );
        let other = SigningKey::random(std::time::Duration::from_secs(900));
        assert_eq!(
            other.verify(path, e.as_deref(), s.as_deref(), 1_500),
            Err(SignError::BadSignature)
        );
        assert_eq!(
            ok(path, None, s.as_deref(), 1_500),
            Err(SignError::Malformed)
        );
        assert!(SigningKey::from_bytes(b"short", key.validity).is_err());
        assert!(SigningKey::from_bytes(&[b'k'; 32], key.validity).is_ok());
    }
}
