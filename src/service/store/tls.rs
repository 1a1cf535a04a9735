//! TLS for the PostgreSQL job store: reads libpq's connection parameters `sslmode`,
//! `sslrootcert`, `sslcert`, `sslkey` and `sslcrl` from a `--database postgres://…` URL and makes
//! connections through rustls (pure Rust, `ring` provider). Beside `store::postgres`, which opens
//! every connection (pool and `LISTEN`) through [`PgTarget::connect`].
//!
//! The modes follow libpq (<https://www.postgresql.org/docs/current/libpq-ssl.html>):
//!
//! | `sslmode` | encrypted | server certificate checked |
//! |---|---|---|
//! | `disable` | never | – |
//! | `prefer` (default) | when the server offers TLS and the TLS attempt succeeds (else one plain-text retry, as libpq) | only if a root certificate is given |
//! | `require` | always | only if a root certificate is given (then as `verify-ca`) |
//! | `verify-ca` | always | signed by a trusted CA |
//! | `verify-full` | always | signed by a trusted CA **and** issued for the host name |
//!
//! The root certificates are `sslrootcert=PATH` (PEM), `sslrootcert=system` (the operating
//! system's trusted CAs; as in libpq 16 it implies, and insists on, `verify-full`), or else
//! `~/.postgresql/root.crt` when that file exists. `sslcert=PATH&sslkey=PATH` present a client
//! certificate (for `hostssl … cert` in `pg_hba.conf`). Over a Unix socket `sslmode` is
//! ignored, as in libpq. A parameter the URL does not set is taken, as libpq does, from the
//! environment: `PGSSLMODE`, `PGSSLROOTCERT`, `PGSSLCERT`, `PGSSLKEY`, `PGSSLCRL` (empty means unset).
//!
//! Over 600 lines: the `sslmode` table, certificate and revocation-list loading, the verifier,
//! their typed errors (`PgUrlError`, `ConnectError`, one variant per parameter or cause) and
//! their unit tests belong together.
use postgres::config::{Host, SslMode as PgSslMode};
use postgres::{Client, NoTls};
use rustls::client::danger::{HandshakeSignatureValid, ServerCertVerified, ServerCertVerifier};
use rustls::client::WebPkiServerVerifier;
use rustls::crypto::CryptoProvider;
use rustls::pki_types::pem::PemObject;
use rustls::pki_types::{
    CertificateDer, CertificateRevocationListDer, PrivateKeyDer, ServerName, UnixTime,
};
use rustls::{
    CertificateError, ClientConfig, DigitallySignedStruct, RootCertStore, SignatureScheme,
};
use std::path::PathBuf;
use std::sync::Arc;
use tokio_postgres_rustls::MakeRustlsConnect;

/// Why a `--database postgres://…` URL or its TLS parameters cannot be used: each cause names
/// the parameter (never the credentials).
#[derive(Debug, thiserror::Error)]
pub enum PgUrlError {
    #[error("--database: expected postgres://USER@HOST:PORT/DBNAME")]
    Scheme,
    /// A percent-encoded parameter name or value (`what`) is not UTF-8.
    #[error("--database: {what} is not valid UTF-8 once decoded")]
    NotUtf8 { what: String },
    #[error(
        "--database: sslmode=allow is not supported (it would try plain text \
         first); use sslmode=prefer or sslmode=disable"
    )]
    SslModeAllow,
    #[error(
        "--database: sslmode={mode:?} is not a known sslmode (expected one of {})",
        SslMode::NAMES
    )]
    SslModeUnknown { mode: String },
    /// The client library does not parse the rest of the URL.
    #[error("--database: not a valid PostgreSQL URL: {0}")]
    Url(#[source] postgres::Error),
    #[error(
        "--database: sslrootcert=system needs sslmode=verify-full (got sslmode={}): a \
         public CA signs certificates for anyone, so only the host name check makes it safe",
        .mode.name()
    )]
    SystemRootsNeedVerifyFull { mode: SslMode },
    #[error("--database: sslrootcert is empty (expected a PEM file path)")]
    EmptyRootCert,
    #[error(
        "--database: sslmode={} needs the certificate of the CA that signed the server's \
         certificate: add sslrootcert=PATH (PEM), or sslrootcert=system for the operating \
         system's trusted CAs (or install it as ~/.postgresql/root.crt)",
        .mode.name()
    )]
    NoRootCert { mode: SslMode },
    #[error(
        "--database: sslcrl needs a root certificate (sslrootcert): revocation is \
         checked along the chain to a trusted CA, and sslmode={} without one checks no \
         chain",
        .mode.name()
    )]
    CrlWithoutRoot { mode: SslMode },
    #[error("--database: sslcert and sslkey go together (a client certificate and its key)")]
    CertWithoutKey,
    /// The PEM file of `param=path` does not read (`label`: what was looked for).
    #[error("--database: {param}={path}: cannot read PEM ({label}): {source}")]
    Pem {
        param: &'static str,
        path: String,
        label: &'static str,
        #[source]
        source: rustls::pki_types::pem::Error,
    },
    #[error("--database: {param}={path}: no PEM block -----BEGIN {label}----- in it")]
    NoPem {
        param: &'static str,
        path: String,
        label: &'static str,
    },
    #[error("--database: sslrootcert={path}: not a usable CA certificate: {source}")]
    BadCa {
        path: String,
        #[source]
        source: rustls::Error,
    },
    /// `sslrootcert=system` found no CA in the operating system's store (the first error met).
    #[error(
        "--database: sslrootcert=system: no trusted CA certificate found in the \
         operating system's store{}",
        .first.as_ref().map(|e| format!(" ({e})")).unwrap_or_default()
    )]
    NoSystemCa {
        first: Option<rustls_native_certs::Error>,
    },
    #[error("--database: TLS set-up: {0}")]
    TlsSetUp(#[source] rustls::Error),
    /// The verifier over the root certificates (and CRLs) could not be built.
    #[error("--database: sslrootcert: {0}")]
    Verifier(#[source] rustls::client::VerifierBuilderError),
    #[error("--database: sslkey={path}: cannot read a PEM private key: {source}")]
    Key {
        path: String,
        #[source]
        source: rustls::pki_types::pem::Error,
    },
    #[error("--database: sslcert/sslkey: {0}")]
    ClientAuth(#[source] rustls::Error),
    /// A cause above whose parameters came (partly) from libpq's environment variables.
    #[error("{source} (taken from the environment: {})", .variables.join(", "))]
    FromEnvironment {
        variables: Vec<&'static str>,
        source: Box<PgUrlError>,
    },
}

/// Why a connection to PostgreSQL failed: the hosts and `sslmode` tried, the cause, and with
/// `sslmode=prefer` the failure of the plain-text retry.
#[derive(Debug, thiserror::Error)]
#[error(
    "connecting to PostgreSQL at {hosts} (sslmode={}): {failure}{}",
    .mode.name(),
    .plain_retry.as_ref().map(|r| format!("; the plain-text retry of sslmode=prefer failed too: {r}")).unwrap_or_default()
)]
pub struct ConnectError {
    pub hosts: String,
    pub mode: SslMode,
    pub failure: Box<ConnectFailure>,
    /// The plain-text retry's failure (`failure` then is the TLS attempt's).
    pub plain_retry: Option<String>,
}

/// The cause of a [`ConnectError`].
#[derive(Debug, thiserror::Error)]
pub enum ConnectFailure {
    /// The TLS handshake or the server's certificate failed; `why` in words.
    #[error("the server's certificate failed verification: {tls}; {why}")]
    Certificate {
        tls: rustls::Error,
        why: CertificateProblem,
    },
    /// Any other failure: the server's refusal or the client library's error (`detail`), and
    /// a hint for the usual misconfigurations.
    #[error("{detail}{hint}")]
    Other { detail: String, hint: &'static str },
}

/// Why the server's certificate was refused, in the terms of the URL's parameters.
#[derive(Debug, thiserror::Error)]
pub enum CertificateProblem {
    #[error("it is not signed by a CA trusted here (sslrootcert={roots})")]
    UnknownIssuer { roots: String },
    #[error(
        "it was not issued for the host name in the URL (sslmode=verify-ca checks \
         the CA only)"
    )]
    NotForName,
    #[error("it has expired")]
    Expired,
    #[error("it has been revoked (sslcrl={crl})")]
    Revoked { crl: String },
    #[error("sslcrl={crl} has no CRL from the issuer of a certificate in its chain")]
    UnknownRevocationStatus { crl: String },
    #[error("the CRL in sslcrl={crl} is past its next update")]
    ExpiredRevocationList { crl: String },
    #[error("it was rejected")]
    Rejected,
    #[error("the TLS handshake failed")]
    Handshake,
}

/// libpq's `sslmode` values (`allow` is not offered: the client library cannot fall back from
/// plain text to TLS).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SslMode {
    Disable,
    Prefer,
    Require,
    VerifyCa,
    VerifyFull,
}

impl SslMode {
    pub const NAMES: &'static str = "disable, prefer, require, verify-ca, verify-full";

    pub fn parse(s: &str) -> Result<Self, PgUrlError> {
        Ok(match s {
            "disable" => Self::Disable,
            "prefer" => Self::Prefer,
            "require" => Self::Require,
            "verify-ca" => Self::VerifyCa,
            "verify-full" => Self::VerifyFull,
            "allow" => return Err(PgUrlError::SslModeAllow),
            other => {
                return Err(PgUrlError::SslModeUnknown {
                    mode: other.to_string(),
                })
            }
        })
    }

    pub fn name(self) -> &'static str {
        match self {
            Self::Disable => "disable",
            Self::Prefer => "prefer",
            Self::Require => "require",
            Self::VerifyCa => "verify-ca",
            Self::VerifyFull => "verify-full",
        }
    }

    fn verifies(self) -> bool {
        matches!(self, Self::VerifyCa | Self::VerifyFull)
    }
}

/// Where trusted root certificates come from.
#[derive(Debug, Clone, PartialEq)]
pub enum RootCerts {
    /// None given and no `~/.postgresql/root.crt`: certificates are not checked.
    None,
    /// A PEM file (`sslrootcert=PATH`, or libpq's default `~/.postgresql/root.crt`).
    File(PathBuf),
    /// `sslrootcert=system`: the operating system's trust store.
    System,
}

/// A parsed `--database` URL: the client configuration and how to secure its connections.
pub struct PgTarget {
    pub config: postgres::Config,
    pub mode: SslMode,
    pub roots: RootCerts,
    /// `sslcrl`: revoked certificates (PEM CRLs), checked with the chain.
    crl: Option<PathBuf>,
    /// Built once; `None` for `sslmode=disable` or when every host is a Unix socket.
    tls: Option<MakeRustlsConnect>,
    /// `host:port, …`, for messages (never the password).
    hosts: String,
}

impl std::fmt::Debug for PgTarget {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("PgTarget")
            .field("hosts", &self.hosts)
            .field("mode", &self.mode)
            .field("roots", &self.roots)
            .finish()
    }
}

/// The parameters this module takes out of the URL before the client library parses it.
#[derive(Debug, Default)]
struct TlsParams {
    sslmode: Option<String>,
    sslrootcert: Option<String>,
    sslcert: Option<String>,
    sslkey: Option<String>,
    sslcrl: Option<String>,
}

/// Split libpq's TLS parameters off a URL's query; the rest of the URL is kept verbatim.
fn split_tls_params(url: &str) -> Result<(String, TlsParams), PgUrlError> {
    let Some((base, query)) = url.split_once('?') else {
        return Ok((url.to_string(), TlsParams::default()));
    };
    let mut kept = Vec::new();
    let mut p = TlsParams::default();
    for pair in query.split('&').filter(|s| !s.is_empty()) {
        let (k, v) = pair.split_once('=').unwrap_or((pair, ""));
        let decode = |s: &str, what: &str| {
            percent_encoding::percent_decode_str(s)
                .decode_utf8()
                .map(|c| c.into_owned())
                .map_err(|_| PgUrlError::NotUtf8 {
                    what: what.to_string(),
                })
        };
        let slot = match decode(k, "a parameter name")?.as_str() {
            "sslmode" => &mut p.sslmode,
            "sslrootcert" => &mut p.sslrootcert,
            "sslcert" => &mut p.sslcert,
            "sslkey" => &mut p.sslkey,
            "sslcrl" => &mut p.sslcrl,
            _ => {
                kept.push(pair);
                continue;
            }
        };
        *slot = Some(decode(v, k)?);
    }
    let rest = if kept.is_empty() {
        base.to_string()
    } else {
        format!("{base}?{}", kept.join("&"))
    };
    Ok((rest, p))
}

/// libpq's default root certificate file, when it exists.
fn default_root_file() -> Option<PathBuf> {
    let home = std::env::var_os("HOME")?;
    let p = PathBuf::from(home).join(".postgresql/root.crt");
    p.is_file().then_some(p)
}

fn provider() -> Arc<CryptoProvider> {
    Arc::new(rustls::crypto::ring::default_provider())
}

/// Every `-----BEGIN {label}-----` object of the PEM file given as `param=path`; none is an
/// error naming the parameter.
fn load_pem<T: PemObject>(
    path: &str,
    param: &'static str,
    label: &'static str,
) -> Result<Vec<T>, PgUrlError> {
    let items = T::pem_file_iter(path)
        .and_then(|it| it.collect::<Result<Vec<_>, _>>())
        .map_err(|source| PgUrlError::Pem {
            param,
            path: path.to_string(),
            label,
            source,
        })?;
    if items.is_empty() {
        return Err(PgUrlError::NoPem {
            param,
            path: path.to_string(),
            label,
        });
    }
    Ok(items)
}

fn load_certs(path: &str, what: &'static str) -> Result<Vec<CertificateDer<'static>>, PgUrlError> {
    load_pem(path, what, "CERTIFICATE")
}

/// The CRLs of `sslcrl=PATH` (PEM). As libpq with OpenSSL's CRL_CHECK_ALL, every certificate
/// of the chain below the trust anchor must then be covered by a CRL of its issuer.
fn load_crls(
    path: &std::path::Path,
) -> Result<Vec<CertificateRevocationListDer<'static>>, PgUrlError> {
    load_pem(&path.display().to_string(), "sslcrl", "X509 CRL")
}

fn root_store(roots: &RootCerts) -> Result<RootCertStore, PgUrlError> {
    let mut store = RootCertStore::empty();
    match roots {
        RootCerts::None => {}
        RootCerts::File(p) => {
            let path = p.display().to_string();
            for c in load_certs(&path, "sslrootcert")? {
                store.add(c).map_err(|source| PgUrlError::BadCa {
                    path: path.clone(),
                    source,
                })?;
            }
        }
        RootCerts::System => {
            let found = rustls_native_certs::load_native_certs();
            let (added, _) = store.add_parsable_certificates(found.certs);
            if added == 0 {
                return Err(PgUrlError::NoSystemCa {
                    first: found.errors.into_iter().next(),
                });
            }
        }
    }
    Ok(store)
}

/// Accepts any certificate (`prefer`/`require` without a root certificate, as libpq does) but
/// still checks the handshake signatures, so the session is encrypted to whoever holds the key
/// of the certificate presented.
#[derive(Debug)]
struct EncryptOnly(Arc<CryptoProvider>);

impl ServerCertVerifier for EncryptOnly {
    fn verify_server_cert(
        &self,
        _end_entity: &CertificateDer<'_>,
        _intermediates: &[CertificateDer<'_>],
        _server_name: &ServerName<'_>,
        _ocsp: &[u8],
        _now: UnixTime,
    ) -> Result<ServerCertVerified, rustls::Error> {
        Ok(ServerCertVerified::assertion())
    }

    fn verify_tls12_signature(
        &self,
        message: &[u8],
        cert: &CertificateDer<'_>,
        dss: &DigitallySignedStruct,
    ) -> Result<HandshakeSignatureValid, rustls::Error> {
        rustls::crypto::verify_tls12_signature(
            message,
            cert,
            dss,
            &self.0.signature_verification_algorithms,
        )
    }

    fn verify_tls13_signature(
        &self,
        message: &[u8],
        cert: &CertificateDer<'_>,
        dss: &DigitallySignedStruct,
    ) -> Result<HandshakeSignatureValid, rustls::Error> {
        rustls::crypto::verify_tls13_signature(
            message,
            cert,
            dss,
            &self.0.signature_verification_algorithms,
        )
    }

    fn supported_verify_schemes(&self) -> Vec<SignatureScheme> {
        self.0.signature_verification_algorithms.supported_schemes()
    }
}

/// `verify-ca`: the chain must lead to a trusted root, the host name is not compared. WebPKI
/// checks the chain before the name, so a name mismatch means the chain was good.
#[derive(Debug)]
struct ChainOnly(Arc<WebPkiServerVerifier>);

impl ServerCertVerifier for ChainOnly {
    fn verify_server_cert(
        &self,
        end_entity: &CertificateDer<'_>,
        intermediates: &[CertificateDer<'_>],
        server_name: &ServerName<'_>,
        ocsp: &[u8],
        now: UnixTime,
    ) -> Result<ServerCertVerified, rustls::Error> {
        match self
            .0
            .verify_server_cert(end_entity, intermediates, server_name, ocsp, now)
        {
            Err(rustls::Error::InvalidCertificate(
                CertificateError::NotValidForName | CertificateError::NotValidForNameContext { .. },
            )) => Ok(ServerCertVerified::assertion()),
            other => other,
        }
    }

    fn verify_tls12_signature(
        &self,
        message: &[u8],
        cert: &CertificateDer<'_>,
        dss: &DigitallySignedStruct,
    ) -> Result<HandshakeSignatureValid, rustls::Error> {
        self.0.verify_tls12_signature(message, cert, dss)
    }

    fn verify_tls13_signature(
        &self,
        message: &[u8],
        cert: &CertificateDer<'_>,
        dss: &DigitallySignedStruct,
    ) -> Result<HandshakeSignatureValid, rustls::Error> {
        self.0.verify_tls13_signature(message, cert, dss)
    }

    fn supported_verify_schemes(&self) -> Vec<SignatureScheme> {
        self.0.supported_verify_schemes()
    }
}

fn client_config(
    mode: SslMode,
    roots: &RootCerts,
    crl: Option<&std::path::Path>,
    client_cert: Option<(&str, &str)>,
) -> Result<ClientConfig, PgUrlError> {
    let provider = provider();
    let builder = ClientConfig::builder_with_provider(provider.clone())
        .with_safe_default_protocol_versions()
        .map_err(PgUrlError::TlsSetUp)?;
    let verifier: Arc<dyn ServerCertVerifier> = if *roots == RootCerts::None {
        Arc::new(EncryptOnly(provider.clone()))
    } else {
        let webpki = WebPkiServerVerifier::builder_with_provider(
            Arc::new(root_store(roots)?),
            provider.clone(),
        )
        .with_crls(match crl {
            Some(path) => load_crls(path)?,
            None => Vec::new(),
        })
        .build()
        .map_err(PgUrlError::Verifier)?;
        if mode == SslMode::VerifyFull {
            webpki
        } else {
            // libpq: with a root certificate, `prefer`/`require` check the chain like verify-ca.
            Arc::new(ChainOnly(webpki))
        }
    };
    let builder = builder
        .dangerous()
        .with_custom_certificate_verifier(verifier);
    let mut config = match client_cert {
        None => builder.with_no_client_auth(),
        Some((cert, key)) => {
            let certs = load_certs(cert, "sslcert")?;
            let key = PrivateKeyDer::from_pem_file(key).map_err(|source| PgUrlError::Key {
                path: key.to_string(),
                source,
            })?;
            builder
                .with_client_auth_cert(certs, key)
                .map_err(PgUrlError::ClientAuth)?
        }
    };
    // PostgreSQL 17's direct TLS negotiation (`sslnegotiation=direct`) requires this ALPN.
    config.alpn_protocols = vec![b"postgresql".to_vec()];
    Ok(config)
}

/// Parse a `--database` URL (already known to start with `postgres://` or `postgresql://`),
/// including its TLS parameters (or libpq's environment variables for those it lacks), and
/// load the certificates it names.
pub fn parse(url: &str) -> Result<PgTarget, PgUrlError> {
    parse_with(url, default_root_file(), &|k| std::env::var(k).ok())
}

/// libpq's environment variables for the TLS parameters.
const TLS_ENV: [&str; 5] = [
    "PGSSLMODE",
    "PGSSLROOTCERT",
    "PGSSLCERT",
    "PGSSLKEY",
    "PGSSLCRL",
];

/// [`parse`] with libpq's default root certificate file and the environment given (tests
/// pass `None` and an empty environment).
fn parse_with(
    url: &str,
    default_root: Option<PathBuf>,
    env: &dyn Fn(&str) -> Option<String>,
) -> Result<PgTarget, PgUrlError> {
    let (rest, mut p) = split_tls_params(url)?;
    let mut from_env = Vec::new();
    let slots = [
        &mut p.sslmode,
        &mut p.sslrootcert,
        &mut p.sslcert,
        &mut p.sslkey,
        &mut p.sslcrl,
    ];
    for (slot, name) in slots.into_iter().zip(TLS_ENV) {
        if slot.is_none() {
            if let Some(v) = env(name).filter(|v| !v.is_empty()) {
                *slot = Some(v);
                from_env.push(name);
            }
        }
    }
    parse_params(&rest, p, default_root).map_err(|e| {
        if from_env.is_empty() {
            e
        } else {
            PgUrlError::FromEnvironment {
                variables: from_env,
                source: Box::new(e),
            }
        }
    })
}

fn parse_params(
    rest: &str,
    p: TlsParams,
    default_root: Option<PathBuf>,
) -> Result<PgTarget, PgUrlError> {
    let mut config = rest.parse::<postgres::Config>().map_err(PgUrlError::Url)?;
    let system = p.sslrootcert.as_deref() == Some("system");
    let mode = match p.sslmode.as_deref() {
        Some(m) => SslMode::parse(m)?,
        // libpq 16: sslrootcert=system defaults to the only mode that makes it meaningful.
        None if system => SslMode::VerifyFull,
        None => SslMode::Prefer,
    };
    if system && mode != SslMode::VerifyFull {
        return Err(PgUrlError::SystemRootsNeedVerifyFull { mode });
    }
    let roots = match p.sslrootcert {
        Some(_) if system => RootCerts::System,
        Some(path) if path.is_empty() => return Err(PgUrlError::EmptyRootCert),
        Some(path) => RootCerts::File(PathBuf::from(path)),
        None => default_root.map_or(RootCerts::None, RootCerts::File),
    };
    if mode.verifies() && roots == RootCerts::None {
        return Err(PgUrlError::NoRootCert { mode });
    }
    let crl = match p.sslcrl {
        None => None,
        Some(path) if path.is_empty() => None,
        Some(_) if roots == RootCerts::None => return Err(PgUrlError::CrlWithoutRoot { mode }),
        Some(path) => Some(PathBuf::from(path)),
    };
    let client_cert = match (&p.sslcert, &p.sslkey) {
        (Some(c), Some(k)) => Some((c.as_str(), k.as_str())),
        (None, None) => None,
        _ => return Err(PgUrlError::CertWithoutKey),
    };
    let hosts = config
        .get_hosts()
        .iter()
        .enumerate()
        .map(|(i, h)| {
            let port = config
                .get_ports()
                .get(i)
                .or(config.get_ports().first())
                .copied()
                .unwrap_or(5432);
            match h {
                Host::Tcp(name) => format!("{name}:{port}"),
                Host::Unix(dir) => format!("{}/.s.PGSQL.{port}", dir.display()),
            }
        })
        .collect::<Vec<_>>()
        .join(", ");
    let all_unix = !config.get_hosts().is_empty()
        && config
            .get_hosts()
            .iter()
            .all(|h| matches!(h, Host::Unix(_)));
    let effective = if all_unix { SslMode::Disable } else { mode };
    config.ssl_mode(match effective {
        SslMode::Disable => PgSslMode::Disable,
        SslMode::Prefer => PgSslMode::Prefer,
        _ => PgSslMode::Require,
    });
    let tls = if effective == SslMode::Disable {
        None
    } else {
        Some(MakeRustlsConnect::new(client_config(
            mode,
            &roots,
            crl.as_deref(),
            client_cert,
        )?))
    };
    Ok(PgTarget {
        config,
        mode,
        roots,
        crl,
        tls,
        hosts,
    })
}

impl PgTarget {
    /// `host:port` of every host in the URL.
    pub fn hosts(&self) -> &str {
        &self.hosts
    }

    /// A new connection, with an error that says which server, which mode and why.
    ///
    /// `prefer` falls back as libpq does: when the TLS attempt fails (the handshake, the
    /// certificate check with a root certificate given, or the server refusing the encrypted
    /// session, e.g. a `hostnossl` line), one more attempt is made in plain text, logged as a
    /// warning. A server answering "no TLS" is taken in plain text by the client library itself.
    pub fn connect(&self) -> Result<Client, ConnectError> {
        let Some(tls) = &self.tls else {
            return self.config.connect(NoTls).map_err(|e| self.explain(&e));
        };
        let first = match self.config.connect(tls.clone()) {
            Ok(c) => return Ok(c),
            Err(e) if self.mode == SslMode::Prefer && Self::plain_retry_helps(&e) => e,
            Err(e) => return Err(self.explain(&e)),
        };
        let why = self.explain(&first);
        let mut plain = self.config.clone();
        plain.ssl_mode(PgSslMode::Disable);
        match plain.connect(NoTls) {
            Ok(c) => {
                tracing::warn!(
                    hosts = %self.hosts,
                    "{why}; connected in plain text instead (sslmode=prefer falls back as libpq \
                     does; sslmode=require or verify-full refuses plain text)"
                );
                Ok(c)
            }
            Err(e) => Err(ConnectError {
                plain_retry: Some(failure(&e)),
                ..why
            }),
        }
    }

    /// Whether libpq's `prefer` would retry in plain text after this failure of the TLS
    /// attempt: a failed handshake, or an error the server sent in the encrypted session.
    /// Not an unreachable host (a plain retry would fail the same way).
    fn plain_retry_helps(e: &postgres::Error) -> bool {
        rustls_error(e).is_some() || e.as_db_error().is_some()
    }

    fn crl_label(&self) -> String {
        self.crl
            .as_ref()
            .map_or("none".into(), |p| p.display().to_string())
    }

    fn roots_label(&self) -> String {
        match &self.roots {
            RootCerts::None => "none".into(),
            RootCerts::File(p) => p.display().to_string(),
            RootCerts::System => "system".into(),
        }
    }

    fn explain(&self, e: &postgres::Error) -> ConnectError {
        let failure = if let Some(tls) = rustls_error(e) {
            let why = match &tls {
                rustls::Error::InvalidCertificate(CertificateError::UnknownIssuer) => {
                    CertificateProblem::UnknownIssuer {
                        roots: self.roots_label(),
                    }
                }
                rustls::Error::InvalidCertificate(
                    CertificateError::NotValidForName
                    | CertificateError::NotValidForNameContext { .. },
                ) => CertificateProblem::NotForName,
                rustls::Error::InvalidCertificate(
                    CertificateError::Expired | CertificateError::ExpiredContext { .. },
                ) => CertificateProblem::Expired,
                rustls::Error::InvalidCertificate(CertificateError::Revoked) => {
                    CertificateProblem::Revoked {
                        crl: self.crl_label(),
                    }
                }
                rustls::Error::InvalidCertificate(CertificateError::UnknownRevocationStatus) => {
                    CertificateProblem::UnknownRevocationStatus {
                        crl: self.crl_label(),
                    }
                }
                rustls::Error::InvalidCertificate(
                    CertificateError::ExpiredRevocationList
                    | CertificateError::ExpiredRevocationListContext { .. },
                ) => CertificateProblem::ExpiredRevocationList {
                    crl: self.crl_label(),
                },
                rustls::Error::InvalidCertificate(_) => CertificateProblem::Rejected,
                _ => CertificateProblem::Handshake,
            };
            ConnectFailure::Certificate { tls, why }
        } else {
            let detail = failure(e);
            let hint = if detail.contains("server does not support TLS") {
                " (its postgresql.conf has ssl = off: turn it on, or use sslmode=prefer/disable)"
            } else if detail.contains("no encryption") && self.mode == SslMode::Disable {
                " (the server's pg_hba.conf only accepts TLS here: drop sslmode=disable)"
            } else {
                ""
            };
            ConnectFailure::Other { detail, hint }
        };
        ConnectError {
            hosts: self.hosts.clone(),
            mode: self.mode,
            failure: Box::new(failure),
            plain_retry: None,
        }
    }
}

/// A connection error that is not a certificate failure: the server's own message if it
/// refused, else the client library's.
fn failure(e: &postgres::Error) -> String {
    match e.as_db_error() {
        Some(db) => format!("the server refused: {}", db.message()),
        None => e.to_string(),
    }
}

/// The rustls error behind a connection error, if the TLS handshake is what failed.
fn rustls_error(e: &postgres::Error) -> Option<rustls::Error> {
    let mut cur: Option<&(dyn std::error::Error + 'static)> = std::error::Error::source(e);
    while let Some(err) = cur {
        if let Some(r) = err.downcast_ref::<rustls::Error>() {
            return Some(r.clone());
        }
        // `io::Error::source` skips the wrapped error itself; look inside.
        if let Some(inner) = err
            .downcast_ref::<std::io::Error>()
            .and_then(|io| io.get_ref())
            .and_then(|i| i.downcast_ref::<rustls::Error>())
        {
            return Some(inner.clone());
        }
        cur = err.source();
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    /// [`parse`] with an empty environment, whatever this machine's `PGSSL*` are.
    fn parse_no_env(url: &str) -> Result<PgTarget, PgUrlError> {
        parse_with(url, default_root_file(), &|_| None)
    }

    /// As if `~/.postgresql/root.crt` did not exist, whatever this machine has.
    fn err(url: &str) -> String {
        parse_with(url, None, &|_| None)
            .map(|_| ())
            .expect_err(url)
            .to_string()
    }

    #[test]
    fn default_is_prefer_and_tls_params_are_stripped() {
        let t =
            parse_no_env("postgres://u@db.example:6543/ashlar?application_name=x").expect("parse");
        assert_eq!(t.mode, SslMode::Prefer);
        assert_eq!(t.config.get_application_name(), Some("x"));
        assert_eq!(t.hosts(), "db.example:6543");
        let (rest, p) = split_tls_params(
            "postgres://h/d?sslmode=require&connect_timeout=3&sslrootcert=%2Ftmp%2Fca.pem",
        )
        .expect("split");
        assert_eq!(rest, "postgres://h/d?connect_timeout=3");
        assert_eq!(p.sslmode.as_deref(), Some("require"));
        assert_eq!(p.sslrootcert.as_deref(), Some("/tmp/ca.pem"));
        assert!(matches!(
            parse_no_env("postgres://h/d?sslmode=disable")
                .expect("parse")
                .mode,
            SslMode::Disable
        ));
    }

    #[test]
    fn unknown_or_unsupported_sslmode_is_named() {
        let e = err("postgres://h/d?sslmode=verify_full");
        assert!(
            e.contains("sslmode=\"verify_full\"") && e.contains("verify-full"),
            "{e}"
        );
        let e = err("postgres://h/d?sslmode=allow");
        assert!(e.contains("sslmode=allow"), "{e}");
    }

    #[test]
    fn verification_needs_a_root_certificate() {
        let e = err("postgres://h/d?sslmode=verify-full");
        assert!(e.contains("sslrootcert"), "{e}");
        let e = err("postgres://h/d?sslmode=verify-ca&sslrootcert=/nonexistent/ca.pem");
        assert!(e.contains("sslrootcert=/nonexistent/ca.pem"), "{e}");
        let e = err("postgres://h/d?sslmode=require&sslrootcert=system");
        assert!(e.contains("verify-full"), "{e}");
        let e = err("postgres://h/d?sslcert=/x.pem");
        assert!(e.contains("sslkey"), "{e}");
    }

    #[test]
    fn a_revocation_list_needs_a_root_certificate() {
        let e = err("postgres://h/d?sslcrl=/tmp/revoked.crl");
        assert!(e.contains("sslcrl") && e.contains("sslrootcert"), "{e}");
        let crl = |k: &str| (k == "PGSSLCRL").then(|| "/tmp/revoked.crl".to_string());
        let e = parse_with("postgres://h/d?sslmode=require", None, &crl)
            .map(|_| ())
            .expect_err("PGSSLCRL without a CA")
            .to_string();
        assert!(e.contains("sslcrl") && e.contains("PGSSLCRL"), "{e}");
        // Empty means unset, as in libpq.
        parse_with("postgres://h/d?sslcrl=", None, &|_| None).expect("empty sslcrl");
    }

    #[test]
    fn a_file_without_certificates_is_refused() {
        let p = std::env::temp_dir().join(format!("ashlar-notacert-{}.pem", std::process::id()));
        std::fs::write(&p, "hello\n").expect("write");
        let e = err(&format!(
            "postgres://h/d?sslmode=verify-full&sslrootcert={}",
            p.display()
        ));
        assert!(
            e.contains("no PEM block -----BEGIN CERTIFICATE-----"),
            "{e}"
        );
        std::fs::remove_file(p).ok();
    }

    #[test]
    fn unix_sockets_ignore_sslmode() {
        let t = parse_no_env("postgres://u@%2Fvar%2Frun%2Fpostgresql/d?sslmode=require")
            .expect("parse");
        assert!(t.tls.is_none());
        assert_eq!(t.config.get_ssl_mode(), PgSslMode::Disable);
    }

    #[test]
    fn environment_fills_what_the_url_lacks_and_is_named_in_errors() {
        let env = |k: &str| match k {
            "PGSSLMODE" => Some("disable".to_string()),
            "PGSSLCERT" => Some(String::new()),
            _ => None,
        };
        let t = parse_with("postgres://h/d", None, &env).expect("parse");
        assert_eq!(t.mode, SslMode::Disable);
        // The URL wins over the environment.
        let t = parse_with("postgres://h/d?sslmode=prefer", None, &env).expect("parse");
        assert_eq!(t.mode, SslMode::Prefer);
        // A bad value from the environment names the variable.
        let bad = |k: &str| (k == "PGSSLMODE").then(|| "verify-everything".to_string());
        let e = parse_with("postgres://h/d", None, &bad)
            .map(|_| ())
            .expect_err("bad PGSSLMODE")
            .to_string();
        assert!(
            e.contains("verify-everything") && e.contains("PGSSLMODE"),
            "{e}"
        );
        // A verifying mode from the environment with no root certificate anywhere.
        let verify = |k: &str| (k == "PGSSLMODE").then(|| "verify-full".to_string());
        let e = parse_with("postgres://h/d", None, &verify)
            .map(|_| ())
            .expect_err("verify-full without a CA")
            .to_string();
        assert!(e.contains("sslrootcert") && e.contains("PGSSLMODE"), "{e}");
        // A client certificate needs its key, wherever each comes from.
        let cert = |k: &str| (k == "PGSSLCERT").then(|| "/nonexistent/client.crt".to_string());
        let e = parse_with("postgres://h/d?sslmode=disable", None, &cert)
            .map(|_| ())
            .expect_err("sslcert without sslkey")
            .to_string();
        assert!(e.contains("sslkey") && e.contains("PGSSLCERT"), "{e}");
    }
}
