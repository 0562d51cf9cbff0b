//! The header dict of an `.npy` array, parsed as numpy reads it
//! (`numpy.lib.format`: `ast.literal_eval` of a Python literal, which must be a
//! dict with exactly the keys `descr`, `fortran_order` and `shape`), never by
//! searching its text: a key inside a string value, a duplicate key, a missing
//! or extra key, or any text after the dict is refused.

/// The three entries of an `.npy` header.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(crate) struct NpyHeader {
    /// The dtype string, e.g. `<f8` (a structured dtype, a list, is refused).
    pub descr: String,
    /// Whether the data are in column-major (Fortran) order.
    pub fortran_order: bool,
    /// The dimensions (empty for a 0-d array).
    pub shape: Vec<u64>,
}

/// One value of the dict.
enum Value {
    Str(String),
    Bool(bool),
    Tuple(Vec<u64>),
}

/// A cursor over the header text.
struct Parser<'a> {
    text: &'a [u8],
    at: usize,
}

impl Parser<'_> {
    fn skip_space(&mut self) {
        while self
            .text
            .get(self.at)
            .is_some_and(|c| matches!(c, b' ' | b'\t' | b'\n' | b'\r'))
        {
            self.at += 1;
        }
    }

    /// Skips spaces and takes `c` if it comes next.
    fn eat(&mut self, c: u8) -> bool {
        self.skip_space();
        if self.text.get(self.at) == Some(&c) {
            self.at += 1;
            true
        } else {
            false
        }
    }

    fn expect(&mut self, c: u8, what: &str) -> Result<(), String> {
        if self.eat(c) {
            Ok(())
        } else {
            Err(format!(
                "malformed .npy header: expected `{}` {what} at byte {}",
                c as char, self.at
            ))
        }
    }

    /// A quoted string without escapes (`'...'` or `"..."`).
    fn string(&mut self) -> Result<String, String> {
        self.skip_space();
        let quote = match self.text.get(self.at) {
            Some(&q @ (b'\'' | b'"')) => q,
            _ => {
                return Err(format!(
                    "malformed .npy header: expected a quoted string at byte {}",
                    self.at
                ));
            }
        };
        let start = self.at + 1;
        let len = self.text[start..]
            .iter()
            .position(|&c| c == quote || c == b'\\' || c == b'\n')
            .filter(|&n| self.text[start + n] == quote)
            .ok_or_else(|| "malformed .npy header: unterminated or escaped string".to_string())?;
        self.at = start + len + 1;
        core::str::from_utf8(&self.text[start..start + len])
            .map(str::to_string)
            .map_err(|_| "malformed .npy header: a string is not UTF-8".to_string())
    }

    /// A decimal integer (digits only).
    fn integer(&mut self) -> Result<u64, String> {
        self.skip_space();
        let start = self.at;
        while self.text.get(self.at).is_some_and(u8::is_ascii_digit) {
            self.at += 1;
        }
        core::str::from_utf8(&self.text[start..self.at])
            .ok()
            .and_then(|d| d.parse().ok())
            .ok_or_else(|| {
                format!(
                    "malformed `shape` in the .npy header: expected a dimension at byte {start}"
                )
            })
    }

    /// A tuple of integers: `()`, `(n,)`, `(n, m)`, `(n, m,)`; `(n)` is an
    /// integer in Python, not a tuple, and is refused as numpy refuses it.
    fn tuple(&mut self) -> Result<Vec<u64>, String> {
        self.expect(b'(', "(a shape tuple)")?;
        let mut dims = Vec::new();
        if self.eat(b')') {
            return Ok(dims);
        }
        loop {
            dims.push(self.integer()?);
            let comma = self.eat(b',');
            if self.eat(b')') {
                if dims.len() == 1 && !comma {
                    return Err("malformed `shape` in the .npy header: `(n)` is not a tuple".into());
                }
                return Ok(dims);
            }
            if !comma {
                return Err("malformed `shape` in the .npy header: expected `,` or `)`".into());
            }
        }
    }

    fn value(&mut self) -> Result<Value, String> {
        self.skip_space();
        let rest = &self.text[self.at..];
        for (word, b) in [(&b"True"[..], true), (&b"False"[..], false)] {
            let after = rest.get(word.len()).copied();
            if rest.starts_with(word)
                && !after.is_some_and(|c| c.is_ascii_alphanumeric() || c == b'_')
            {
                self.at += word.len();
                return Ok(Value::Bool(b));
            }
        }
        match rest.first() {
            Some(b'\'' | b'"') => self.string().map(Value::Str),
            Some(b'(') => self.tuple().map(Value::Tuple),
            _ => Err(format!(
                "malformed .npy header: unsupported value at byte {}",
                self.at
            )),
        }
    }
}

/// Parses the header text of an `.npy` array (the dict, padded with spaces
/// and a newline) as numpy does, or says what is wrong.
pub(crate) fn parse_npy_header(text: &str) -> Result<NpyHeader, String> {
    let mut p = Parser {
        text: text.as_bytes(),
        at: 0,
    };
    p.expect(b'{', "(the header dict)")?;
    let (mut descr, mut fortran, mut shape) = (None, None, None);
    if !p.eat(b'}') {
        loop {
            let key = p.string()?;
            p.expect(b':', "after a key")?;
            let value = p.value()?;
            let slot_taken = match (key.as_str(), value) {
                ("descr", Value::Str(s)) => descr.replace(s).is_some(),
                ("fortran_order", Value::Bool(b)) => fortran.replace(b).is_some(),
                ("shape", Value::Tuple(t)) => shape.replace(t).is_some(),
                ("descr" | "fortran_order" | "shape", _) => {
                    return Err(format!("malformed .npy header: `{key}` has the wrong type"));
                }
                _ => {
                    return Err(format!(
                        "malformed .npy header: unexpected key {:?} (numpy writes only \
                         descr, fortran_order and shape)",
                        key.chars().take(40).collect::<String>()
                    ));
                }
            };
            if slot_taken {
                return Err(format!("malformed .npy header: key `{key}` given twice"));
            }
            let comma = p.eat(b',');
            if p.eat(b'}') {
                break;
            }
            if !comma {
                return Err(format!(
                    "malformed .npy header: expected `,` or `}}` at byte {}",
                    p.at
                ));
            }
        }
    }
    p.skip_space();
    if p.at != p.text.len() {
        return Err(format!(
            "malformed .npy header: text after the dict at byte {}",
            p.at
        ));
    }
    let missing = |k: &str| format!("the .npy header has no `{k}`");
    Ok(NpyHeader {
        descr: descr.ok_or_else(|| missing("descr"))?,
        fortran_order: fortran.ok_or_else(|| missing("fortran_order"))?,
        shape: shape.ok_or_else(|| missing("shape"))?,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numpys_own_headers_parse() {
        let h = parse_npy_header(
            "{'descr': '<f8', 'fortran_order': False, 'shape': (3, 4), }          \n",
        )
        .unwrap();
        assert_eq!(h.descr, "<f8");
        assert!(!h.fortran_order);
        assert_eq!(h.shape, [3, 4]);
        let h = parse_npy_header("{\"shape\": (5,), \"fortran_order\": True, \"descr\": \">f8\"}")
            .unwrap();
        assert_eq!(
            (h.descr.as_str(), h.fortran_order, &h.shape[..]),
            (">f8", true, &[5][..])
        );
        let h = parse_npy_header("{'descr': '|O', 'fortran_order': False, 'shape': (), }").unwrap();
        assert!(h.shape.is_empty());
    }

    #[test]
    fn a_key_hidden_in_a_string_is_not_read() {
        // The old text search found `'fortran_order': True` inside descr.
        let e = parse_npy_header(
            "{'descr': \"'fortran_order': True, '<f8\", 'fortran_order': False, 'shape': (2,)}",
        );
        let h = e.unwrap();
        assert!(!h.fortran_order);
        assert_ne!(h.descr, "<f8");
    }

    #[test]
    fn duplicate_missing_extra_keys_and_trailing_text_are_refused() {
        for (text, want) in [
            (
                "{'descr': '<f8', 'fortran_order': True, 'fortran_order': False, 'shape': (2,)}",
                "given twice",
            ),
            ("{'descr': '<f8', 'shape': (2,)}", "no `fortran_order`"),
            (
                "{'descr': '<f8', 'fortran_order': False, 'shape': (2,), 'x': 'y'}",
                "unexpected key",
            ),
            (
                "{'descr': '<f8', 'fortran_order': False, 'shape': (2,)} {'shape': (3,)}",
                "text after",
            ),
            (
                "{'descr': '<f8', 'fortran_order': False, 'shape': (2)}",
                "not a tuple",
            ),
            (
                "{'descr': '<f8', 'fortran_order': 'True', 'shape': (2,)}",
                "wrong type",
            ),
            (
                "{'descr': '<f8', 'fortran_order': Truex, 'shape': (2,)}",
                "unsupported",
            ),
            (
                "{'descr': '<f\\x38', 'fortran_order': False, 'shape': (2,)}",
                "escaped",
            ),
            (
                "{'descr': '<f8', 'fortran_order': False, 'shape': (-2,)}",
                "dimension",
            ),
            (
                "{'descr': '<f8', 'fortran_order': False, 'shape': [2]}",
                "unsupported",
            ),
            ("", "expected `{`"),
        ] {
            let e = parse_npy_header(text).unwrap_err();
            assert!(e.contains(want), "{text}: {e}");
        }
    }
}
