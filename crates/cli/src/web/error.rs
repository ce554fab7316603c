//! The API's one error shape: a 4xx/5xx status with `{"error": "..."}`,
//! the cause first, then what to do.

use axum::Json;
use axum::http::StatusCode;
use axum::response::{IntoResponse, Response};
use drivebus_master::{DriveError, SdoAbort, SdoError};

/// An API error: status and message.
#[derive(Debug)]
pub struct ApiError {
    /// HTTP status.
    pub status: StatusCode,
    /// Cause first, then what to do.
    pub message: String,
}

/// A handler's result.
pub type ApiResult<T> = Result<T, ApiError>;

impl ApiError {
    /// 400: the request itself is wrong.
    pub fn bad(message: impl Into<String>) -> ApiError {
        ApiError { status: StatusCode::BAD_REQUEST, message: message.into() }
    }

    /// 404: no such node or object.
    pub fn not_found(message: impl Into<String>) -> ApiError {
        ApiError { status: StatusCode::NOT_FOUND, message: message.into() }
    }

    /// 409: the device is in a state that does not allow it.
    pub fn conflict(message: impl Into<String>) -> ApiError {
        ApiError { status: StatusCode::CONFLICT, message: message.into() }
    }

    /// An SDO transfer that failed: the device's abort (404 for an absent
    /// object, 422 for a refused value), a timeout (504) or the bus (502).
    pub fn sdo(node: u8, index: u16, sub: u8, e: &SdoError) -> ApiError {
        let at = format!("{index:04X}h:{sub:02X}h on node {node}");
        if let SdoError::OtherClient { cause, .. } = e {
            return ApiError::sdo(node, index, sub, cause);
        }
        match e.abort_code() {
            Some(code) => ApiError::abort(code, &at),
            None => match e {
                SdoError::Timeout => ApiError {
                    status: StatusCode::GATEWAY_TIMEOUT,
                    message: format!(
                        "no SDO answer from node {node} for {at}: is the node on the bus and powered?"
                    ),
                },
                SdoError::InvalidRequest(m) | SdoError::Decode(m) => {
                    ApiError::bad(format!("{m}: give the data type (\"type\": \"u16\")"))
                }
                _ => ApiError {
                    status: StatusCode::BAD_GATEWAY,
                    message: format!("{e} at {at}: check the bus connection"),
                },
            },
        }
    }

    /// A device's SDO abort `at` an object: 404 for an absent object or
    /// sub-index, 422 for any other refusal, with the CiA 301 text.
    pub fn abort(code: SdoAbort, at: &str) -> ApiError {
        let text = code.description().unwrap_or("manufacturer-specific abort");
        let status = match code {
            SdoAbort::NO_OBJECT | SdoAbort::NO_SUB_INDEX => StatusCode::NOT_FOUND,
            _ => StatusCode::UNPROCESSABLE_ENTITY,
        };
        ApiError {
            status,
            message: format!(
                "{text} (SDO abort {:08X}h) at {at}: check the index, sub-index, access and value range in the device's EDS",
                code.0
            ),
        }
    }

    /// A drive operation that failed.
    pub fn drive(node: u8, e: &DriveError) -> ApiError {
        match e {
            DriveError::Sdo(s) => ApiError::sdo(node, 0x6040, 0, s),
            DriveError::Timeout { .. } => ApiError {
                status: StatusCode::GATEWAY_TIMEOUT,
                message: format!("node {node}: {e}; read 6041h and 603Fh to see why"),
            },
            _ => {
                ApiError::conflict(format!("node {node}: {e}; fault-reset and enable the drive, then retry"))
            }
        }
    }
}

impl IntoResponse for ApiError {
    fn into_response(self) -> Response {
        (self.status, Json(serde_json::json!({ "error": self.message }))).into_response()
    }
}
