//! Errors of [`open`](crate::open): they name the URL and the cause.

use std::fmt;
use std::io;

/// Why a bus could not be opened.
#[derive(Debug)]
pub enum Cause {
    /// The URL does not follow the grammar of [`BusUrl`](crate::BusUrl).
    BadUrl(String),
    /// The transport failed (connect, handshake, device, ...).
    Io(io::Error),
    /// The URL is valid but this build or platform cannot serve it.
    Unsupported(String),
}

/// An error opening a bus URL: `cannot open URL: cause`.
#[derive(Debug)]
pub struct TransportError {
    /// The URL as given.
    pub url: String,
    /// What went wrong.
    pub cause: Cause,
}

impl TransportError {
    /// An error about `url`.
    pub fn new(url: &str, cause: Cause) -> Self {
        TransportError { url: url.to_owned(), cause }
    }
    pub(crate) fn bad_url(url: &str, why: impl Into<String>) -> Self {
        TransportError::new(url, Cause::BadUrl(why.into()))
    }
}

impl fmt::Display for TransportError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match &self.cause {
            Cause::BadUrl(why) => write!(f, "bad bus URL `{}`: {why}", self.url),
            Cause::Io(e) => write!(f, "cannot open `{}`: {e}", self.url),
            Cause::Unsupported(why) => write!(f, "cannot open `{}`: {why}", self.url),
        }
    }
}

impl std::error::Error for TransportError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match &self.cause {
            Cause::Io(e) => Some(e),
            _ => None,
        }
    }
}
