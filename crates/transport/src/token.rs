//! The session token that keeps a stray client out of a physics server.
//!
//! A 64-bit value written as 16 hexadecimal digits. Resolution order, the
//! same on both command lines: the `--token` argument, else the environment
//! variable [`TOKEN_ENV`], else (server only) a fresh random token that the
//! server prints for the client to use.

use crate::link::LinkError;
use std::fmt;
use std::str::FromStr;

/// Environment variable holding the session token.
pub const TOKEN_ENV: &str = "ECHOTHIGH_TOKEN";

/// A session token.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct SessionToken(pub u64);

/// Where a resolved token came from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TokenSource {
    /// The command line.
    Argument,
    /// The [`TOKEN_ENV`] environment variable.
    Environment,
    /// Freshly generated (print it for the client).
    Generated,
}

impl SessionToken {
    /// A random token from the OS-seeded generator.
    pub fn generate() -> Self {
        SessionToken(rand::random())
    }

    /// The token from the command line, else from [`TOKEN_ENV`], else
    /// `None`. A present but malformed value is an error naming it.
    pub fn from_arg_or_env(arg: Option<&str>) -> Result<Option<(Self, TokenSource)>, LinkError> {
        if let Some(text) = arg {
            return Ok(Some((text.parse()?, TokenSource::Argument)));
        }
        match std::env::var(TOKEN_ENV) {
            Ok(text) => Ok(Some((text.parse()?, TokenSource::Environment))),
            Err(_) => Ok(None),
        }
    }

    /// Server side: [`Self::from_arg_or_env`], else a generated token.
    pub fn resolve_or_generate(arg: Option<&str>) -> Result<(Self, TokenSource), LinkError> {
        Ok(Self::from_arg_or_env(arg)?
            .unwrap_or_else(|| (Self::generate(), TokenSource::Generated)))
    }
}

impl fmt::Display for SessionToken {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{:016x}", self.0)
    }
}

impl FromStr for SessionToken {
    type Err = LinkError;

    fn from_str(s: &str) -> Result<Self, LinkError> {
        let t = s.trim();
        let bad = || LinkError::BadToken { text: s.to_owned() };
        if t.is_empty() || t.len() > 16 || !t.bytes().all(|b| b.is_ascii_hexdigit()) {
            return Err(bad());
        }
        u64::from_str_radix(t, 16)
            .map(SessionToken)
            .map_err(|_| bad())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn display_and_parse_round_trip() {
        let t = SessionToken(0x00ab_cdef_0123_4567);
        assert_eq!(t.to_string(), "00abcdef01234567");
        assert_eq!("00abcdef01234567".parse::<SessionToken>().unwrap(), t);
        assert_eq!("FF".parse::<SessionToken>().unwrap(), SessionToken(255));
    }

    #[test]
    fn malformed_tokens_are_errors_naming_the_text() {
        for bad in ["", "xyz", "12345678901234567", "+12", "-1"] {
            let e = bad.parse::<SessionToken>().unwrap_err();
            assert!(e.to_string().contains(&format!("{bad:?}")), "{e}");
        }
    }

    #[test]
    fn argument_wins() {
        let (t, src) = SessionToken::resolve_or_generate(Some("2a")).unwrap();
        assert_eq!((t, src), (SessionToken(42), TokenSource::Argument));
    }
}
