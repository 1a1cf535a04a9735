//! Shared artifact storage: where a worker publishes a finished job's files (histories,
//! MCAP, summary) so that the API process on another machine can serve them. Part of the
//! worker, imported by the pool and by `http::downloads`, importing neither; built on
//! `object_store` (a local or shared directory as
//! `file:///…`, or S3-compatible storage as `s3://bucket/prefix` when built with the `s3`
//! feature).
//!
//! Without `--artifacts`, artifacts stay in each process's `--data DIR/jobs/<uuid>/`, which is
//! enough when every process is given the same (shared) directory.
use object_store::path::Path as StorePath;
use object_store::{ObjectStore, PutPayload};
use std::path::Path;
use std::sync::{Arc, OnceLock};
use uuid::Uuid;

/// Artifact files a job may leave, the only names ever published or fetched.
pub const ARTIFACT_NAMES: &[&str] = &[
    "summary.json",
    "result.json",
    "histories.csv",
    "trajectory.mcap",
    "fragility.svg",
];

/// An object store plus the prefix jobs live under (`<prefix>/jobs/<uuid>/<file>`).
pub struct ArtifactStore {
    store: Arc<dyn ObjectStore>,
    prefix: StorePath,
    url: String,
}

impl std::fmt::Debug for ArtifactStore {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ArtifactStore")
            .field("url", &self.url)
            .finish()
    }
}

/// Why shared artifact storage could not be opened, written, listed or read. `url` is the
/// storage's URL without its query (which may carry credentials).
#[derive(Debug, thiserror::Error)]
pub enum ArtifactError {
    /// The runtime that drives the object store could not start (kept for every later call).
    #[error("starting the artifact runtime: {0}")]
    Runtime(#[source] Arc<std::io::Error>),
    /// `--artifacts` is not a URL (`url` as given).
    #[error(
        "--artifacts {url:?}: not a URL ({source}); expected file:///DIR or s3://BUCKET/PREFIX"
    )]
    NotAUrl {
        url: String,
        #[source]
        source: url::ParseError,
    },
    #[error("--artifacts {url}: a file:// URL takes no options")]
    FileOptions { url: String },
    /// The local root directory could not be created.
    #[error("--artifacts {url}: {source}")]
    Root {
        url: String,
        #[source]
        source: std::io::Error,
    },
    #[error("--artifacts {url}: not a local directory")]
    NotLocal { url: String },
    #[error(
        "--artifacts {url}: this ashlar was built without S3 support (cargo build --features s3)"
    )]
    NoS3 { url: String },
    /// A query option of an `s3://` URL that `object_store` does not know (`option` as given).
    #[error("--artifacts {url}: unknown S3 option {option:?} in the URL (expected object_store's names: endpoint, region, allow_http, virtual_hosted_style_request, skip_signature, …)")]
    S3Option { url: String, option: String },
    /// `object_store` refused the URL or its options.
    #[error("--artifacts {url}: {source}")]
    Open {
        url: String,
        #[source]
        source: object_store::Error,
    },
    /// The start-up probe (one listing) failed: wrong bucket, endpoint or credentials.
    #[error("--artifacts {url}: the storage is not reachable: {source}")]
    Unreachable {
        url: String,
        #[source]
        source: object_store::Error,
    },
    #[error("the artifact probe panicked")]
    ProbePanicked,
    /// A job's artifact file could not be read for publishing (`path`; logged).
    #[error("the server could not read the job's artifacts")]
    ReadLocal {
        path: std::path::PathBuf,
        #[source]
        source: std::io::Error,
    },
    /// An artifact could not be uploaded (logged).
    #[error("the server could not publish the job's artifacts to shared storage")]
    Publish {
        url: String,
        #[source]
        source: object_store::Error,
    },
    /// Listing, deleting or downloading failed.
    #[error("{url}: {source}")]
    Storage {
        url: String,
        #[source]
        source: object_store::Error,
    },
    /// The download task on the artifact runtime did not finish.
    #[error("artifact fetch task: {0}")]
    Task(#[source] tokio::task::JoinError),
    /// A downloaded artifact could not be written to `path`.
    #[error("{}: {source}", path.display())]
    Write {
        path: std::path::PathBuf,
        #[source]
        source: std::io::Error,
    },
}

/// The runtime blocking callers (worker threads) drive object-store futures on. A static, so
/// it is never dropped inside an async context.
fn runtime() -> Result<&'static tokio::runtime::Runtime, ArtifactError> {
    static RT: OnceLock<Result<tokio::runtime::Runtime, Arc<std::io::Error>>> = OnceLock::new();
    RT.get_or_init(|| {
        tokio::runtime::Builder::new_multi_thread()
            .worker_threads(1)
            .thread_name("ashlar-artifacts")
            .enable_all()
            .build()
            .map_err(Arc::new)
    })
    .as_ref()
    .map_err(|e| ArtifactError::Runtime(e.clone()))
}

impl ArtifactStore {
    /// Open `file:///ABSOLUTE/DIR` or `s3://BUCKET/PREFIX` (with the `s3` feature). A plain
    /// absolute path is taken as a directory.
    ///
    /// S3 settings come from the usual `AWS_*` environment variables (`AWS_ACCESS_KEY_ID`,
    /// `AWS_SECRET_ACCESS_KEY`, `AWS_REGION`, `AWS_ENDPOINT`, `AWS_ALLOW_HTTP`, …), then from
    /// the URL's query, which wins:
    /// `s3://bucket/prefix?endpoint=http://127.0.0.1:9000&allow_http=true` (any name
    /// `object_store`'s `AmazonS3ConfigKey` accepts; keep secrets in the environment). The bucket is probed once here, so a wrong endpoint, bucket or
    /// credential stops the process at start-up instead of failing every job.
    pub fn open(url: &str) -> Result<Self, ArtifactError> {
        let full = if url.starts_with('/') {
            format!("file://{url}")
        } else {
            url.to_string()
        };
        let mut parsed = url::Url::parse(&full).map_err(|source| ArtifactError::NotAUrl {
            url: url.to_string(),
            source,
        })?;
        let options: Vec<(String, String)> = parsed.query_pairs().into_owned().collect();
        parsed.set_query(None);
        // Shown in logs and errors: without the query, which may carry credentials.
        let shown = parsed.to_string();
        if parsed.scheme() == "file" {
            if !options.is_empty() {
                return Err(ArtifactError::FileOptions { url: shown });
            }
            // The local store does not create its root; workers must agree on it existing.
            std::fs::create_dir_all(parsed.path()).map_err(|source| ArtifactError::Root {
                url: shown.clone(),
                source,
            })?;
        }
        let (store, prefix) = if parsed.scheme() == "s3" {
            object_store::parse_url_opts(&parsed, s3_options(&shown, options)?)
        } else if parsed.scheme() == "file" {
            // Rooted at the directory, with empty directories removed after a delete: a deleted
            // job leaves no `jobs/<uuid>/` behind, and the cleanup stops at the root (which the
            // processes must agree exists) instead of walking up to `/`.
            let dir = parsed
                .to_file_path()
                .map_err(|()| ArtifactError::NotLocal { url: shown.clone() })?;
            object_store::local::LocalFileSystem::new_with_prefix(dir).map(|fs| {
                let fs: Box<dyn ObjectStore> = Box::new(fs.with_automatic_cleanup(true));
                (fs, StorePath::default())
            })
        } else {
            object_store::parse_url(&parsed)
        }
        .map_err(|source| match parsed.scheme() {
            "s3" if !cfg!(feature = "s3") => ArtifactError::NoS3 { url: shown.clone() },
            _ => ArtifactError::Open {
                url: shown.clone(),
                source,
            },
        })?;
        let out = Self {
            store: Arc::from(store),
            prefix,
            url: shown,
        };
        if parsed.scheme() != "file" {
            out.probe()?;
        }
        Ok(out)
    }

    /// One listing of the prefix (empty on a fresh bucket, an error when the bucket, endpoint
    /// or credentials are wrong). On its own thread: the caller may be inside a runtime.
    fn probe(&self) -> Result<(), ArtifactError> {
        let store = self.store.clone();
        let prefix = self.prefix.clone();
        let rt = runtime()?;
        let res = std::thread::spawn(move || {
            rt.block_on(store.list_with_delimiter(Some(&prefix)))
                .map(|_| ())
        })
        .join()
        .map_err(|_| ArtifactError::ProbePanicked)?;
        res.map_err(|source| ArtifactError::Unreachable {
            url: self.url.clone(),
            source,
        })
    }

    /// `<prefix>/jobs/<tail…>`: where every job's artifacts live.
    fn under_jobs(&self, tail: &[&str]) -> StorePath {
        let parts = self.prefix.parts().map(|p| p.as_ref().to_string());
        let tail = std::iter::once("jobs").chain(tail.iter().copied());
        StorePath::from_iter(parts.chain(tail.map(String::from)))
    }

    fn location(&self, id: Uuid, name: &str) -> StorePath {
        self.under_jobs(&[&id.hyphenated().to_string(), name])
    }

    /// Upload the artifacts found in a job's directory (blocking; worker threads).
    pub fn publish_dir(&self, id: Uuid, dir: &Path) -> Result<(), ArtifactError> {
        let rt = runtime()?;
        for name in ARTIFACT_NAMES {
            let path = dir.join(name);
            let bytes = match std::fs::read(&path) {
                Ok(b) => b,
                Err(e) if e.kind() == std::io::ErrorKind::NotFound => continue,
                Err(source) => {
                    tracing::error!(path = %path.display(), error = %source, "reading an artifact");
                    return Err(ArtifactError::ReadLocal { path, source });
                }
            };
            let loc = self.location(id, name);
            rt.block_on(self.store.put(&loc, PutPayload::from(bytes)))
                .map_err(|source| {
                    tracing::error!(url = %self.url, error = %source, "publishing an artifact");
                    ArtifactError::Publish {
                        url: self.url.clone(),
                        source,
                    }
                })?;
        }
        Ok(())
    }

    /// Bytes of every job's published artifacts (one listing of `<prefix>/jobs/`; blocking).
    pub fn total_bytes(&self) -> Result<u64, ArtifactError> {
        use futures_util::TryStreamExt;
        let jobs = self.under_jobs(&[]);
        runtime()?
            .block_on(
                self.store
                    .list(Some(&jobs))
                    .try_fold(0u64, |n, m| async move { Ok(n.saturating_add(m.size)) }),
            )
            .map_err(|e| self.storage(e))
    }

    /// A listing, delete or download failure of this store.
    fn storage(&self, source: object_store::Error) -> ArtifactError {
        ArtifactError::Storage {
            url: self.url.clone(),
            source,
        }
    }

    /// Remove a deleted job's published artifacts (blocking: not on an async runtime's
    /// thread). Absent files are fine: a job that failed early published nothing.
    pub fn remove(&self, id: Uuid) -> Result<(), ArtifactError> {
        let rt = runtime()?;
        for name in ARTIFACT_NAMES {
            let loc = self.location(id, name);
            match rt.block_on(self.store.delete(&loc)) {
                Ok(()) | Err(object_store::Error::NotFound { .. }) => {}
                Err(e) => return Err(self.storage(e)),
            }
        }
        Ok(())
    }

    /// Download one artifact whole into memory, None when absent. For small files and tests:
    /// serving goes through [`ArtifactStore::ensure_local`], which streams to disk.
    pub async fn fetch(&self, id: Uuid, name: &str) -> Result<Option<bytes::Bytes>, ArtifactError> {
        let loc = self.location(id, name);
        let store = self.store.clone();
        // On the artifact runtime: an S3 client's connections belong to one runtime.
        let task = runtime()?.spawn(async move {
            match store.get(&loc).await {
                Ok(r) => r.bytes().await.map(Some),
                Err(object_store::Error::NotFound { .. }) => Ok(None),
                Err(e) => Err(e),
            }
        });
        task.await
            .map_err(ArtifactError::Task)?
            .map_err(|e| self.storage(e))
    }

    /// Download one artifact into the file `to`, chunk by chunk as the store hands them over:
    /// memory stays one chunk whatever the artifact's size (a 300 MB trajectory asked for by
    /// eight clients at once must not cost 2.4 GB). `Ok(false)` when absent.
    pub async fn fetch_to(&self, id: Uuid, name: &str, to: &Path) -> Result<bool, ArtifactError> {
        let loc = self.location(id, name);
        let store = self.store.clone();
        let to = to.to_path_buf();
        let url = self.url.clone();
        let task = runtime()?.spawn(async move {
            use futures_util::StreamExt;
            use tokio::io::AsyncWriteExt;
            let got = match store.get(&loc).await {
                Ok(r) => r,
                Err(object_store::Error::NotFound { .. }) => return Ok(false),
                Err(source) => return Err(ArtifactError::Storage { url, source }),
            };
            let write = |source| ArtifactError::Write {
                path: to.clone(),
                source,
            };
            let mut file = tokio::fs::File::create(&to).await.map_err(write)?;
            let mut chunks = got.into_stream();
            while let Some(chunk) = chunks.next().await {
                let chunk = chunk.map_err(|source| ArtifactError::Storage {
                    url: url.clone(),
                    source,
                })?;
                file.write_all(&chunk).await.map_err(write)?;
            }
            file.flush().await.map_err(write)?;
            Ok(true)
        });
        task.await.map_err(ArtifactError::Task)?
    }
}

/// S3 options: `AWS_*` environment variables, then the URL's query (validated: an unknown
/// option is named, not ignored).
fn s3_options(
    shown: &str,
    query: Vec<(String, String)>,
) -> Result<Vec<(String, String)>, ArtifactError> {
    let mut opts: Vec<(String, String)> = std::env::vars()
        .filter(|(k, _)| k.starts_with("AWS_"))
        .map(|(k, v)| (k.to_ascii_lowercase(), v))
        .collect();
    for (k, v) in query {
        let key = k.to_ascii_lowercase();
        #[cfg(feature = "s3")]
        if key.parse::<object_store::aws::AmazonS3ConfigKey>().is_err() {
            return Err(ArtifactError::S3Option {
                url: shown.to_string(),
                option: k,
            });
        }
        #[cfg(not(feature = "s3"))]
        let _ = shown;
        opts.push((key, v));
    }
    Ok(opts)
}

impl ArtifactStore {
    /// Make sure `dir/<name>` (the job `id`'s local directory) exists, downloading it from this
    /// store when this process did not run the job. Streamed to disk (see
    /// [`ArtifactStore::fetch_to`]); concurrent requests for the same file wait for one
    /// download instead of each starting its own. Errors are logged; the caller then answers
    /// as if the artifact were missing.
    pub async fn ensure_local(&self, id: Uuid, dir: &Path, name: &str) {
        let path = dir.join(name);
        if tokio::fs::try_exists(&path).await.unwrap_or(false) {
            return;
        }
        let gate = download_gate(id, name);
        {
            let _one_at_a_time = gate.lock().await;
            // Another request may have downloaded it meanwhile.
            if !tokio::fs::try_exists(&path).await.unwrap_or(false) {
                self.download(id, dir, name).await;
            }
        }
        release_gate(id, name, gate);
    }

    /// Download `name` into `dir` under a temporary name, then rename it into place: a
    /// concurrent reader never sees half a file.
    async fn download(&self, id: Uuid, dir: &Path, name: &str) {
        let path = dir.join(name);
        let tmp = dir.join(format!(".{name}.{}", Uuid::new_v4().simple()));
        if let Err(e) = tokio::fs::create_dir_all(dir).await {
            tracing::error!(dir = %dir.display(), error = %e, "caching an artifact");
            return;
        }
        match self.fetch_to(id, name, &tmp).await {
            Ok(true) => {
                if let Err(e) = tokio::fs::rename(&tmp, &path).await {
                    tracing::error!(path = %path.display(), error = %e, "caching an artifact");
                }
            }
            Ok(false) => {}
            Err(e) => tracing::error!(error = %e, "fetching an artifact"),
        }
        let _ = tokio::fs::remove_file(&tmp).await;
    }
}

/// One async lock per artifact being downloaded (see [`ArtifactStore::ensure_local`]).
type Gates =
    std::sync::Mutex<std::collections::HashMap<(Uuid, String), Arc<tokio::sync::Mutex<()>>>>;

fn gates() -> &'static Gates {
    static GATES: OnceLock<Gates> = OnceLock::new();
    GATES.get_or_init(Default::default)
}

fn download_gate(id: Uuid, name: &str) -> Arc<tokio::sync::Mutex<()>> {
    let mut g = gates().lock().unwrap_or_else(|p| p.into_inner());
    g.entry((id, name.to_string())).or_default().clone()
}

/// Drop the gate once nobody else holds or waits on it (the map keeps no entry per download).
fn release_gate(id: Uuid, name: &str, gate: Arc<tokio::sync::Mutex<()>>) {
    let mut g = gates().lock().unwrap_or_else(|p| p.into_inner());
    // Ours and the map's: nobody else waits.
    if Arc::strong_count(&gate) <= 2 {
        g.remove(&(id, name.to_string()));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn publishes_and_fetches_through_a_directory() {
        let root = std::env::temp_dir().join(format!("ashlar-artifacts-{}", Uuid::new_v4()));
        let src = root.join("src");
        std::fs::create_dir_all(&src).expect("dir");
        std::fs::write(src.join("histories.csv"), "time,a.x\n0,0\n").expect("write");
        std::fs::write(src.join("unrelated.txt"), "x").expect("write");
        let store = ArtifactStore::open(&format!("file://{}", root.join("shared").display()))
            .expect("open");
        let id = Uuid::new_v4();
        store.publish_dir(id, &src).expect("publish");
        let on_disk = root
            .join("shared/jobs")
            .join(id.to_string())
            .join("histories.csv");
        assert_eq!(
            std::fs::read_to_string(on_disk).expect("published"),
            "time,a.x\n0,0\n"
        );
        let rt = tokio::runtime::Builder::new_current_thread()
            .enable_all()
            .build()
            .expect("rt");
        let got = rt
            .block_on(store.fetch(id, "histories.csv"))
            .expect("fetch");
        assert_eq!(got.as_deref(), Some(&b"time,a.x\n0,0\n"[..]));
        assert_eq!(
            rt.block_on(store.fetch(id, "trajectory.mcap"))
                .expect("fetch"),
            None
        );
        assert!(
            !root
                .join("shared/jobs")
                .join(id.to_string())
                .join("unrelated.txt")
                .exists(),
            "only artifact names are published"
        );
        // The quota's count: the published files, not the unrelated one.
        assert_eq!(store.total_bytes().expect("listing"), 13);
        // A deleted job's files go, with its directory; the root stays; twice is fine.
        store.remove(id).expect("remove");
        store.remove(id).expect("remove again");
        assert!(!root.join("shared/jobs").join(id.to_string()).exists());
        assert!(root.join("shared").is_dir());
        assert_eq!(store.total_bytes().expect("listing"), 0);
        assert_eq!(
            rt.block_on(store.fetch(id, "histories.csv"))
                .expect("fetch"),
            None
        );
        std::fs::remove_dir_all(root).ok();
    }

    #[test]
    fn bad_urls_are_named() {
        let e = ArtifactStore::open("not a url").expect_err("rejected");
        assert!(e.to_string().contains("--artifacts"), "{e}");
        if !cfg!(feature = "s3") {
            let e = ArtifactStore::open("s3://bucket/x").expect_err("rejected");
            assert!(matches!(e, ArtifactError::NoS3 { .. }), "{e}");
            assert!(e.to_string().contains("without S3"), "{e}");
        }
    }
}
