//! The session token: the shared secret that keeps a stray client out of a
//! physics server. It never goes on the wire: the handshake derives
//! per-session keys from it ([`crate::auth`]).
//!
//! Written as [`MIN_TOKEN_DIGITS`] to [`MAX_TOKEN_DIGITS`] hexadecimal
//! digits (64 to 256 bits; case-insensitive). Fewer digits are refused: a
//! 64-bit token is the floor at which guessing online (one Hello per
//! guess, answered at most once per second per source) or offline (one
//! HMAC per guess against a captured Hello) is out of reach. Its entropy
//! cannot be judged from one string; the generated token draws 128 random
//! bits. Resolution order, the same on both command lines: the `--token`
//! argument, else the environment variable [`TOKEN_ENV`], else (server
//! only) a fresh random token that the server prints for the client.

use crate::link::LinkError;
use std::fmt;
use std::str::FromStr;

/// Environment variable holding the session token.
pub const TOKEN_ENV: &str = "ECHOTHIGH_TOKEN";
/// Fewest hexadecimal digits of a token (64 bits).
pub const MIN_TOKEN_DIGITS: usize = 16;
/// Most hexadecimal digits of a token (256 bits).
pub const MAX_TOKEN_DIGITS: usize = 64;
/// Digits of a generated token (128 bits).
const GENERATED_DIGITS: usize = 32;

/// A session token: its hexadecimal digits, lower case.
#[derive(Clone, Copy, PartialEq, Eq, Hash)]
pub struct SessionToken {
    digits: [u8; MAX_TOKEN_DIGITS],
    len: usize,
}

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
    /// A random 128-bit token (32 hex digits) from the OS-seeded generator.
    pub fn generate() -> Self {
        let bits: u128 = rand::random();
        format!("{bits:0width$x}", width = GENERATED_DIGITS)
            .parse()
            .expect("32 hex digits is a valid token")
    }

    /// The token's key material: its lower-case digits as ASCII (the input
    /// keying material of the key derivation).
    pub fn as_bytes(&self) -> &[u8] {
        &self.digits[..self.len]
    }

    /// Number of hexadecimal digits (4 bits each).
    pub fn digits(&self) -> usize {
        self.len
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
        // Only ASCII hex digits are ever stored.
        f.write_str(std::str::from_utf8(self.as_bytes()).unwrap_or("?"))
    }
}

impl fmt::Debug for SessionToken {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        // A secret: never printed by Debug (logs, panics).
        write!(f, "SessionToken({} hex digits)", self.len)
    }
}

impl FromStr for SessionToken {
    type Err = LinkError;

    fn from_str(s: &str) -> Result<Self, LinkError> {
        let t = s.trim();
        let bad = |reason: String| LinkError::BadToken {
            text: s.chars().take(80).collect(),
            reason,
        };
        if let Some(c) = t.chars().find(|c| !c.is_ascii_hexdigit()) {
            return Err(bad(format!("{c:?} is not a hexadecimal digit")));
        }
        if t.len() < MIN_TOKEN_DIGITS || t.len() > MAX_TOKEN_DIGITS {
            return Err(bad(format!(
                "{} digits; a token has {MIN_TOKEN_DIGITS} to {MAX_TOKEN_DIGITS} \
                 (at least 64 bits)",
                t.len()
            )));
        }
        let mut digits = [0u8; MAX_TOKEN_DIGITS];
        for (d, b) in digits.iter_mut().zip(t.bytes()) {
            *d = b.to_ascii_lowercase();
        }
        Ok(SessionToken {
            digits,
            len: t.len(),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn display_and_parse_round_trip_case_insensitively() {
        let t: SessionToken = "00ABcdef01234567".parse().unwrap();
        assert_eq!(t.to_string(), "00abcdef01234567");
        assert_eq!(t, "00abcdef01234567".parse().unwrap());
        assert_eq!(t.digits(), 16);
        let g = SessionToken::generate();
        assert_eq!(g.digits(), GENERATED_DIGITS);
        assert_eq!(g.to_string().parse::<SessionToken>().unwrap(), g);
        assert!(!format!("{g:?}").contains(&g.to_string()), "Debug hides it");
    }

    #[test]
    fn short_or_malformed_tokens_are_errors_naming_the_text() {
        for bad in [
            "",
            "7",
            "2a",
            "0123456789abcde",
            "xyz0123456789abcdef",
            "+123456789abcdef0",
            &"a".repeat(65),
        ] {
            let e = bad.parse::<SessionToken>().unwrap_err().to_string();
            let shown: String = bad.chars().take(80).collect();
            assert!(e.contains(&format!("{shown:?}")), "{e}");
        }
        let e = "7".parse::<SessionToken>().unwrap_err().to_string();
        assert!(e.contains("1 digits") && e.contains("64 bits"), "{e}");
    }

    #[test]
    fn argument_wins() {
        let (t, src) = SessionToken::resolve_or_generate(Some("000000000000002a")).unwrap();
        assert_eq!(src, TokenSource::Argument);
        assert_eq!(t.to_string(), "000000000000002a");
    }
}
