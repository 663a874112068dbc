//! Scene parameters, in the manner of Mitsuba's `$name` with a `<default>`: a scene declares
//! `parameters: { "spp": "64", "wall": "(0.73, 0.73, 0.73)" }` (each value is RON text) and
//! writes `$spp` or `$wall` where a value goes; `-D name=value` on the command line replaces a
//! default. Substitution is textual and happens before parsing (outside strings and
//! comments), and positions in errors are mapped back to the file as written.

use super::SceneError;
use std::collections::BTreeMap;
use std::path::Path;

/// The text after substitution, and where each `$name` was.
pub struct Substituted {
    /// The scene text with every `$name` replaced by its value.
    pub text: String,
    /// Replaced references: (start in `text`, its length there, start in the input, its
    /// length there), in order.
    spans: Vec<(usize, usize, usize, usize)>,
    /// Byte offset of each line's start in the input.
    lines: Vec<usize>,
}

/// A `$name` in the text: byte range and name.
struct Reference {
    start: usize,
    end: usize,
    name: String,
}

/// The `$name` references outside strings and comments.
fn references(text: &str) -> Vec<Reference> {
    let b = text.as_bytes();
    let mut out = Vec::new();
    let mut i = 0;
    while i < b.len() {
        match b[i] {
            b'"' => {
                i += 1;
                while i < b.len() && b[i] != b'"' {
                    i += if b[i] == b'\\' { 2 } else { 1 };
                }
                i += 1;
            }
            b'/' if b.get(i + 1) == Some(&b'/') => {
                while i < b.len() && b[i] != b'\n' {
                    i += 1;
                }
            }
            b'/' if b.get(i + 1) == Some(&b'*') => {
                i += 2;
                while i + 1 < b.len() && !(b[i] == b'*' && b[i + 1] == b'/') {
                    i += 1;
                }
                i += 2;
            }
            b'$' => {
                let start = i;
                i += 1;
                while i < b.len() && (b[i].is_ascii_alphanumeric() || b[i] == b'_') {
                    i += 1;
                }
                out.push(Reference { start, end: i, name: text[start + 1..i].to_owned() });
            }
            _ => i += 1,
        }
    }
    out
}

/// Only the `parameters` of a scene (every other field ignored).
#[derive(serde::Deserialize)]
#[serde(rename = "Scene")]
struct Declared {
    #[serde(default, deserialize_with = "declarations")]
    parameters: BTreeMap<String, String>,
}

/// A scene's `parameters` map, each name declared once.
pub fn declarations<'de, D: serde::Deserializer<'de>>(d: D) -> Result<BTreeMap<String, String>, D::Error> {
    struct V;
    impl<'de> serde::de::Visitor<'de> for V {
        type Value = BTreeMap<String, String>;
        fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
            f.write_str("a map from parameter names to RON text")
        }
        fn visit_map<A: serde::de::MapAccess<'de>>(self, mut map: A) -> Result<Self::Value, A::Error> {
            let mut out = BTreeMap::new();
            while let Some(name) = map.next_key::<String>()? {
                if out.contains_key(&name) {
                    return Err(serde::de::Error::custom(format!("parameter \"{name}\" is declared twice")));
                }
                let value = map.next_value()?;
                out.insert(name, value);
            }
            Ok(out)
        }
    }
    d.deserialize_map(V)
}

impl Substituted {
    /// Replaces every `$name` in `text` by `overrides`' value for it, else the scene's
    /// declared default; `path` names the file in errors.
    pub fn new(text: &str, overrides: &[(String, String)], path: &Path) -> Result<Self, SceneError> {
        let lines = std::iter::once(0).chain(text.match_indices('\n').map(|(i, _)| i + 1)).collect();
        let refs = references(text);
        let mut s = Substituted { text: String::new(), spans: Vec::new(), lines };
        let at = |s: &Substituted, offset: usize, message: String| {
            let (line, col) = s.input_position(offset);
            SceneError { path: path.to_owned(), line, col, message }
        };
        if refs.is_empty() && overrides.is_empty() {
            s.text = text.to_owned();
            return Ok(s);
        }
        // The declared defaults, read with every reference standing in as `()`. A file that
        // cannot be read so has a syntax error (or a bad `parameters`), reported where it is.
        let mut blank = Substituted { text: String::new(), spans: Vec::new(), lines: s.lines.clone() };
        let mut last = 0;
        for r in &refs {
            blank.text.push_str(&text[last..r.start]);
            blank.spans.push((blank.text.len(), 2, r.start, r.end - r.start));
            blank.text.push_str("()");
            last = r.end;
        }
        blank.text.push_str(&text[last..]);
        let options =
            ron::Options::default().with_default_extension(ron::extensions::Extensions::IMPLICIT_SOME);
        let declared = match options.from_str::<Declared>(&blank.text) {
            Ok(d) => d.parameters,
            Err(e) => {
                let (line, col) = blank.map_position(e.span.start.line, e.span.start.col);
                return Err(SceneError { path: path.to_owned(), line, col, message: e.code.to_string() });
            }
        };
        let names = || declared.keys().map(|k| format!("\"{k}\"")).collect::<Vec<_>>().join(", ");
        for (name, _) in overrides {
            if !declared.contains_key(name) {
                let message =
                    format!("-D {name}: the scene declares no such parameter (it declares: {})", names());
                return Err(SceneError { path: path.to_owned(), line: 0, col: 0, message });
            }
        }
        let mut last = 0;
        for r in &refs {
            let value =
                overrides.iter().rev().find(|(n, _)| *n == r.name).map(|(_, v)| v).or(declared.get(&r.name));
            let Some(value) = value else {
                let message = match r.name.is_empty() {
                    true => "`$` must be followed by the name of a parameter".to_owned(),
                    false => format!(
                        "${} is not a declared parameter (`parameters` declares: {})",
                        r.name,
                        names()
                    ),
                };
                return Err(at(&s, r.start, message));
            };
            s.text.push_str(&text[last..r.start]);
            s.spans.push((s.text.len(), value.len(), r.start, r.end - r.start));
            s.text.push_str(value);
            last = r.end;
        }
        s.text.push_str(&text[last..]);
        Ok(s)
    }

    /// 1-based (line, column) in the input of byte `offset` of the input.
    fn input_position(&self, offset: usize) -> (usize, usize) {
        let line = self.lines.partition_point(|&start| start <= offset);
        (line, offset - self.lines[line - 1] + 1)
    }

    /// The input's (line, column) of a 1-based position in the substituted text: inside a
    /// substituted value, the `$name` it came from.
    pub fn map_position(&self, line: usize, col: usize) -> (usize, usize) {
        if self.spans.is_empty() || line == 0 {
            return (line, col);
        }
        // The byte offset in the substituted text.
        let out_offset =
            self.text.split_inclusive('\n').take(line - 1).map(str::len).sum::<usize>() + col - 1;
        let mut shift: isize = 0;
        for &(out, out_len, input, in_len) in &self.spans {
            if out_offset < out {
                break;
            }
            if out_offset < out + out_len {
                return self.input_position(input);
            }
            shift = (input + in_len) as isize - (out + out_len) as isize;
        }
        self.input_position((out_offset as isize + shift).max(0) as usize)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn references_outside_strings_and_comments_are_replaced() {
        let text = "Scene(x: $a, s: \"$a\", // $a\n y: $b /* $b */)";
        let s = Substituted::new(text, &[], Path::new("t")).map(|s| s.text);
        // `a` is not declared (no `parameters`): an error at its place.
        let e = s.unwrap_err();
        assert_eq!((e.line, e.col), (1, 10), "{e}");
        let text =
            "Scene(parameters: {\"a\": \"1\", \"b\": \"2\"},\n x: $a, s: \"$a\", // $a\n y: $b /* $b */)";
        let s = Substituted::new(text, &[("b".into(), "(3, 4)".into())], Path::new("t")).unwrap();
        assert_eq!(
            s.text,
            "Scene(parameters: {\"a\": \"1\", \"b\": \"2\"},\n x: 1, s: \"$a\", // $a\n y: (3, 4) /* $b */)"
        );
        // Positions after a substitution map back to the file as written; inside a value, to
        // its reference.
        assert_eq!(s.map_position(3, 5), (3, 5));
        assert_eq!(s.map_position(3, 13), (3, 9));
        assert_eq!(s.map_position(2, 9), (2, 9 + 1));
        let undeclared = Substituted::new(text, &[("c".into(), "1".into())], Path::new("t"));
        assert!(undeclared.err().unwrap().message.contains("declares no such parameter"));
    }

    /// A syntax error in a file that declares parameters is reported as itself, where it is
    /// (past the references before it), not as the references' fault.
    #[test]
    fn syntax_errors_are_reported_where_they_are() {
        let text = "Scene(parameters: {\"long_name\": \"1\"},\n x: $long_name, y: $long_name,, z: 1)";
        let e = Substituted::new(text, &[], Path::new("t")).err().unwrap();
        assert_eq!((e.line, e.col), (2, 31), "{e}");
        assert!(!e.message.contains("parameter"), "{e}");
    }

    #[test]
    fn a_parameter_declared_twice_is_refused() {
        let text = "Scene(parameters: {\"a\": \"1\", \"a\": \"2\"}, x: $a)";
        let e = Substituted::new(text, &[], Path::new("t")).err().unwrap();
        assert!(e.message.contains("\"a\" is declared twice"), "{e}");
        assert_eq!(e.line, 1, "{e}");
    }
}
