//! Errors of the HTTP layer as RFC 9457 problem details (`application/problem+json`): the edge
//! where the core's typed errors become a problem type per cause (`From<RequestError>`: a
//! request's `SceneError` is `invalid-scene`, its `MotionError` `invalid-motion`, its
//! `RunError::ModelNotApplicable` `model-not-applicable`, a limit `limit-exceeded`, …;
//! `ApiError::store` for `StoreError`; docs/architecture.md). Every failure a client can cause names what was wrong: `pointer` (a
//! JSON pointer into the request body) or `parameter` (a path or query parameter). Internal
//! failures are logged with their cause and reported to the client without it.
use crate::analysis::run::RunError;
use crate::motion::MotionError;
pub use crate::service::request::pointer::{dotted_to_pointer, point_at_named_field};
use crate::service::request::RequestError;
use crate::service::store::StoreError;
use axum::http::{header, HeaderValue, StatusCode};
use axum::response::{IntoResponse, Response};
use serde::Serialize;

/// One error response.
#[derive(Debug, Clone, PartialEq)]
pub struct ApiError {
    pub status: StatusCode,
    /// Short slug; the problem `type` is `urn:ashlar:problem:<kind>`.
    pub kind: &'static str,
    pub title: &'static str,
    pub detail: String,
    /// JSON pointer into the request body (`/scene/blocks/1/vertices`).
    pub pointer: Option<String>,
    /// Name of the offending path or query parameter.
    pub parameter: Option<String>,
    /// Seconds, for 503 answers.
    pub retry_after: Option<u32>,
}

#[derive(Serialize)]
struct Body<'a> {
    #[serde(rename = "type")]
    kind: String,
    title: &'a str,
    status: u16,
    detail: &'a str,
    #[serde(skip_serializing_if = "Option::is_none")]
    pointer: Option<&'a str>,
    #[serde(skip_serializing_if = "Option::is_none")]
    parameter: Option<&'a str>,
}

impl ApiError {
    fn new(
        status: StatusCode,
        kind: &'static str,
        title: &'static str,
        detail: impl Into<String>,
    ) -> Self {
        Self {
            status,
            kind,
            title,
            detail: detail.into(),
            pointer: None,
            parameter: None,
            retry_after: None,
        }
    }

    pub fn with_pointer(mut self, pointer: impl Into<String>) -> Self {
        self.pointer = Some(pointer.into());
        self
    }

    pub fn with_parameter(mut self, name: impl Into<String>) -> Self {
        self.parameter = Some(name.into());
        self
    }

    /// The body is not JSON at all (syntax error, wrong encoding).
    pub fn malformed_json(detail: impl Into<String>) -> Self {
        Self::new(
            StatusCode::BAD_REQUEST,
            "malformed-json",
            "Request body is not valid JSON",
            detail,
        )
    }

    /// The body is JSON but a field is missing, unknown, of the wrong type or out of range.
    pub fn invalid_field(pointer: impl Into<String>, detail: impl Into<String>) -> Self {
        Self::new(
            StatusCode::UNPROCESSABLE_ENTITY,
            "invalid-field",
            "Request field is invalid",
            detail,
        )
        .with_pointer(pointer)
    }

    /// A path or query parameter is malformed.
    pub fn invalid_parameter(name: impl Into<String>, detail: impl Into<String>) -> Self {
        Self::new(
            StatusCode::BAD_REQUEST,
            "invalid-parameter",
            "Request parameter is invalid",
            detail,
        )
        .with_parameter(name)
    }

    /// The ground-motion reader refused the motion ([`MotionError`]): `pointer` names the
    /// member, the detail also the line of an embedded record (`POST /motion`, whose body is
    /// the motion; as a job's motion, through [`RequestError::Motion`]).
    pub fn motion(pointer: impl Into<String>, e: MotionError) -> Self {
        RequestError::Motion {
            pointer: pointer.into(),
            source: e,
        }
        .into()
    }

    /// A configured limit is exceeded by a field of the body (blocks, record length, steps).
    pub fn limit_exceeded(pointer: impl Into<String>, detail: impl Into<String>) -> Self {
        Self::new(
            StatusCode::UNPROCESSABLE_ENTITY,
            "limit-exceeded",
            "Request exceeds a server limit",
            detail,
        )
        .with_pointer(pointer)
    }

    /// A body the server could not read: 413 when it ran over `limit` bytes, else 400 saying
    /// why (cut short, not UTF-8 …).
    pub fn unreadable_body(e: &axum::extract::rejection::BytesRejection, limit: usize) -> Self {
        if e.status() == StatusCode::PAYLOAD_TOO_LARGE {
            Self::payload_too_large(limit)
        } else {
            Self::malformed_json(e.body_text()).with_pointer("")
        }
    }

    pub fn payload_too_large(limit: usize) -> Self {
        Self::new(
            StatusCode::PAYLOAD_TOO_LARGE,
            "payload-too-large",
            "Request body too large",
            format!("the request body exceeds the server's limit of {limit} bytes (see `ashlar serve --max-body-bytes`)"),
        )
        .with_pointer("")
    }

    pub fn unsupported_media_type(got: &str) -> Self {
        Self::new(
            StatusCode::UNSUPPORTED_MEDIA_TYPE,
            "unsupported-media-type",
            "Unsupported media type",
            format!("the body must be sent with Content-Type: application/json, got {got:?}"),
        )
        .with_parameter("Content-Type")
    }

    pub fn not_found(what: &str, id: impl std::fmt::Display) -> Self {
        Self::new(
            StatusCode::NOT_FOUND,
            "not-found",
            "Not found",
            format!("no {what} with id {id}"),
        )
        .with_parameter("id")
    }

    /// Something the request names (e.g. `?block=`) does not exist in an existing resource.
    pub fn not_found_parameter(name: &str, detail: impl Into<String>) -> Self {
        Self::new(StatusCode::NOT_FOUND, "not-found", "Not found", detail).with_parameter(name)
    }

    pub fn no_route(path: &str) -> Self {
        Self::new(
            StatusCode::NOT_FOUND,
            "no-route",
            "No such endpoint",
            format!("no endpoint at {path}; see /openapi.yaml"),
        )
    }

    /// The resource exists but is not in a state that has what was asked for.
    pub fn conflict(detail: impl Into<String>) -> Self {
        Self::new(
            StatusCode::CONFLICT,
            "conflict",
            "Not available in the job's current state",
            detail,
        )
        .with_parameter("id")
    }

    pub fn not_acceptable(detail: impl Into<String>) -> Self {
        Self::new(
            StatusCode::NOT_ACCEPTABLE,
            "not-acceptable",
            "Not acceptable",
            detail,
        )
        .with_parameter("Accept")
    }

    pub fn range_not_satisfiable(detail: impl Into<String>) -> Self {
        Self::new(
            StatusCode::RANGE_NOT_SATISFIABLE,
            "range-not-satisfiable",
            "Range not satisfiable",
            detail,
        )
        .with_parameter("Range")
    }

    pub fn unavailable(detail: impl Into<String>, retry_after: u32) -> Self {
        let mut e = Self::new(
            StatusCode::SERVICE_UNAVAILABLE,
            "unavailable",
            "Service unavailable",
            detail,
        );
        e.retry_after = Some(retry_after);
        e
    }

    /// No valid bearer token (`ashlar serve --tokens`): 401 with `WWW-Authenticate: Bearer`.
    pub fn unauthorized(detail: impl Into<String>) -> Self {
        Self::new(
            StatusCode::UNAUTHORIZED,
            "unauthorized",
            "Authentication required",
            detail,
        )
        .with_parameter("Authorization")
    }

    /// The body did not arrive within `--body-timeout`.
    pub fn request_timeout(secs: f64) -> Self {
        Self::new(
            StatusCode::REQUEST_TIMEOUT,
            "request-timeout",
            "Request body too slow",
            format!(
                "the request body did not arrive within {secs} s (ashlar serve --body-timeout)"
            ),
        )
        .with_pointer("")
    }

    /// A quota of queued work is used up (429, with Retry-After).
    pub fn quota_exceeded(detail: impl Into<String>, retry_after: u32) -> Self {
        let mut e = Self::new(
            StatusCode::TOO_MANY_REQUESTS,
            "quota-exceeded",
            "Quota of queued work exceeded",
            detail,
        );
        e.retry_after = Some(retry_after);
        e
    }

    /// The artifact disk quota is used up (507) until jobs are deleted.
    pub fn insufficient_storage(detail: impl Into<String>) -> Self {
        Self::new(
            StatusCode::INSUFFICIENT_STORAGE,
            "insufficient-storage",
            "Artifact storage quota exceeded",
            detail,
        )
    }

    /// Request headers over `--max-header-bytes` or too many of them (431).
    pub fn headers_too_large(detail: impl Into<String>) -> Self {
        Self::new(
            StatusCode::REQUEST_HEADER_FIELDS_TOO_LARGE,
            "header-fields-too-large",
            "Request header fields too large",
            detail,
        )
    }

    /// A job-store failure, logged in full; the client gets a problem per cause without
    /// internals: a busy or unreachable database is `unavailable` (503, retry after 1 s),
    /// every other cause (a database error, corrupt data, schema, a poisoned lock) `internal`.
    pub fn store(e: StoreError) -> Self {
        match e {
            StoreError::Busy { .. } => {
                tracing::error!(cause = %e, "job store unavailable");
                Self::unavailable("the job store is busy or unreachable; retry shortly", 1)
            }
            other => Self::internal(other),
        }
    }

    /// An internal failure: `cause` goes to the log, the client gets a generic message.
    pub fn internal(cause: impl std::fmt::Display) -> Self {
        tracing::error!(%cause, "internal error");
        Self::new(
            StatusCode::INTERNAL_SERVER_ERROR,
            "internal",
            "Internal server error",
            "the server failed to handle the request; the cause has been logged",
        )
    }

    pub fn type_uri(&self) -> String {
        format!("urn:ashlar:problem:{}", self.kind)
    }
}

/// A refused request body as a problem, its type chosen per cause; the detail is the error's
/// text and the pointer its member ([`RequestError::pointer`]).
impl From<RequestError> for ApiError {
    fn from(e: RequestError) -> Self {
        use RequestError as E;
        let unprocessable = StatusCode::UNPROCESSABLE_ENTITY;
        let (status, kind, title) = match e.cause() {
            E::EmptyBody | E::Syntax(_) => (
                StatusCode::BAD_REQUEST,
                "malformed-json",
                "Request body is not valid JSON",
            ),
            E::Scene { .. } => (unprocessable, "invalid-scene", "Scene is invalid"),
            E::Motion { .. } => (unprocessable, "invalid-motion", "Ground motion is invalid"),
            E::Model(RunError::ModelNotApplicable { .. }) => (
                unprocessable,
                "model-not-applicable",
                "The scene's model cannot represent it",
            ),
            // Any other refusal of `choose_model` is a bug of the caller, not the request's.
            E::Model(other) => return Self::internal(other),
            E::JsonValues { .. }
            | E::BlocksWhileReading { .. }
            | E::RecordsWhileReading
            | E::Vertices { .. }
            | E::PulseCycles { .. }
            | E::Blocks { .. }
            | E::RecordSamples { .. }
            | E::Steps { .. }
            | E::Frames { .. }
            | E::RunWork { .. }
            | E::RunOutput { .. }
            | E::SearchWork { .. }
            | E::TooManyRecords { .. }
            | E::TooManyObservations { .. } => (
                unprocessable,
                "limit-exceeded",
                "Request exceeds a server limit",
            ),
            E::NotAnObject { .. }
            | E::Field { .. }
            | E::OutOfRange { .. }
            | E::AccelerationOutOfRange { .. }
            | E::ExcitationField { .. }
            | E::NoDuration
            | E::NoCriterion { .. }
            | E::Criterion { .. }
            | E::CriterionType { .. }
            | E::NotFreeBlocks { .. }
            | E::Damage { .. }
            | E::NoRecords
            | E::RecordName { .. }
            | E::RecordMissing { .. }
            | E::DuplicateRecord { .. }
            // `cause()` looks through a record's error: its type is its cause's.
            | E::InRecord { .. }
            | E::ZeroHorizontal { .. }
            | E::MotionAndMotions
            | E::NoMotion
            | E::Combine(_)
            | E::Scan(_)
            | E::Fit(_)
            | E::FitNeedsRecords
            | E::Amplitude { .. }
            | E::RangeOrder { .. }
            | E::Tolerance
            | E::ScanPoints { .. }
            | E::Resolution
            | E::ResolutionPoints { .. }
            | E::ResolutionAndScanPoints
            | E::NoObservations
            | E::ObservationArray { .. } => {
                (unprocessable, "invalid-field", "Request field is invalid")
            }
        };
        let mut problem = Self::new(status, kind, title, e.to_string());
        problem.pointer = e.pointer();
        problem
    }
}

impl std::fmt::Display for ApiError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{} {}: {}",
            self.status.as_u16(),
            self.title,
            self.detail
        )
    }
}

impl IntoResponse for ApiError {
    fn into_response(self) -> Response {
        let body = Body {
            kind: self.type_uri(),
            title: self.title,
            status: self.status.as_u16(),
            detail: &self.detail,
            pointer: self.pointer.as_deref(),
            parameter: self.parameter.as_deref(),
        };
        let text = serde_json::to_string(&body).unwrap_or_else(|_| "{}".into());
        let mut resp = (self.status, text).into_response();
        resp.headers_mut().insert(
            header::CONTENT_TYPE,
            HeaderValue::from_static("application/problem+json"),
        );
        if self.status == StatusCode::UNAUTHORIZED {
            resp.headers_mut().insert(
                header::WWW_AUTHENTICATE,
                HeaderValue::from_static("Bearer realm=\"ashlar\""),
            );
        }
        if let Some(s) = self.retry_after {
            resp.headers_mut()
                .insert(header::RETRY_AFTER, HeaderValue::from(s));
        }
        resp
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// One problem per store cause: a busy or unreachable database is 503 with a retry, the
    /// other causes 500; neither shows the database's text to the client.
    #[test]
    fn store_errors_become_a_problem_per_cause() {
        use crate::service::store::Backend;
        let busy = ApiError::store(StoreError::Busy {
            database: Backend::Sqlite,
            detail: "database is locked".into(),
        });
        assert_eq!(
            (busy.status, busy.kind),
            (StatusCode::SERVICE_UNAVAILABLE, "unavailable")
        );
        assert_eq!(busy.retry_after, Some(1));
        assert!(!busy.detail.contains("locked"), "{}", busy.detail);
        let corrupt = ApiError::store(StoreError::corrupt("job status", "\"lost\""));
        assert_eq!(
            (corrupt.status, corrupt.kind),
            (StatusCode::INTERNAL_SERVER_ERROR, "internal")
        );
        assert!(!corrupt.detail.contains("lost"), "{}", corrupt.detail);
    }

    /// A refused request becomes one problem type per cause, at the pointer the cause names;
    /// an error of record `i` of a search keeps its cause's type, re-pointed at `/motions/i`.
    #[test]
    fn request_errors_become_a_problem_per_cause() {
        let problem = |e: RequestError| {
            let p = ApiError::from(e);
            (p.status.as_u16(), p.kind, p.pointer, p.detail)
        };
        let (status, kind, pointer, detail) = problem(RequestError::EmptyBody);
        assert_eq!(
            (status, kind, pointer.as_deref()),
            (400, "malformed-json", Some(""))
        );
        assert_eq!(detail, "the request body is empty; expected a JSON object");
        let steps = RequestError::Steps {
            duration: 10.0,
            time_step: 1e-3,
            steps: 10_000.0,
            limit: 999,
        };
        let (status, kind, pointer, _) = problem(steps);
        assert_eq!(
            (status, kind, pointer.as_deref()),
            (422, "limit-exceeded", Some("/scene/control/duration"))
        );
        let motion = RequestError::Motion {
            pointer: "/motion/horizontal/dt".into(),
            source: MotionError::new("motion.horizontal.dt", None, "must be > 0"),
        };
        let (status, kind, pointer, detail) = problem(RequestError::InRecord {
            index: 2,
            source: Box::new(motion),
        });
        assert_eq!(
            (status, kind, pointer.as_deref()),
            (422, "invalid-motion", Some("/motions/2/horizontal/dt"))
        );
        assert_eq!(detail, "/motions/2/horizontal/dt: must be > 0");
        let (_, kind, pointer, detail) = problem(RequestError::Tolerance);
        assert_eq!(
            (kind, pointer.as_deref()),
            ("invalid-field", Some("/tolerance"))
        );
        assert!(detail.starts_with("/tolerance: "), "{detail}");
        // A refusal of the model other than "not applicable" is the server's bug.
        let (status, kind, pointer, _) = problem(RequestError::Model(RunError::NoDuration));
        assert_eq!((status, kind, pointer), (500, "internal", None));
    }
}
