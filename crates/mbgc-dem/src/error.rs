//! The engine's error: a scene, a parameter set or a request the engine cannot run. The engine
//! reads no files, so its errors name the parameter and the range it expected, and callers that
//! read files add the file's name (`mbgc::Error` converts from this type).

/// Why the engine refused a scene, a parameter or a request.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A request that cannot be run as given; the message names the value and what was expected.
    #[error("{0}")]
    Invalid(String),
}

/// The engine's result type.
pub type Result<T> = std::result::Result<T, Error>;

impl Error {
    /// An [`Error::Invalid`] with this message.
    pub fn invalid(msg: impl Into<String>) -> Self {
        Error::Invalid(msg.into())
    }
}
