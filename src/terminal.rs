//! Text for the terminal: what a scene or another file says (names, values, paths) reaches the
//! terminal inside messages, and must not drive it. Control characters other than newline and
//! tab (ESC starting a colour, a title or a cursor move, a carriage return that overwrites the
//! line, C1 controls) are written as Rust escapes instead.

/// `text` with each control character but `\n` and `\t` written as `\u{..}`.
pub fn safe(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        match c {
            '\n' | '\t' => out.push(c),
            c if c.is_control() => out.extend(c.escape_unicode()),
            c => out.push(c),
        }
    }
    out
}

#[cfg(test)]
mod tests {
    #[test]
    fn control_characters_are_escaped() {
        let s = super::safe("a\u{1b}[31mred\r\u{9b}2J\nnext\tcol ü");
        assert_eq!(s, "a\\u{1b}[31mred\\u{d}\\u{9b}2J\nnext\tcol ü");
    }
}
