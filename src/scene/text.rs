//! Reading line-based text formats (OBJ, ASCII PLY): fields with their columns, for errors
//! that point at line:col.

/// Whitespace-separated fields with their 1-based columns (in characters). Columns are
/// counted on from the previous field, so a line of n bytes costs O(n) however many fields
/// it has.
#[derive(Clone)]
pub struct Fields<'a> {
    s: &'a str,
    i: usize,
    /// Characters in `s[..i]`.
    chars: usize,
}

impl<'a> Fields<'a> {
    pub fn new(s: &'a str) -> Self {
        Fields { s, i: 0, chars: 0 }
    }
}

impl<'a> Iterator for Fields<'a> {
    type Item = (usize, &'a str);
    fn next(&mut self) -> Option<Self::Item> {
        let rest = &self.s[self.i..];
        let start = rest.find(|c: char| !c.is_whitespace())?;
        let tok_start = self.i + start;
        let len = self.s[tok_start..]
            .find(char::is_whitespace)
            .unwrap_or(self.s.len() - tok_start);
        let col = self.chars + rest[..start].chars().count() + 1;
        let tok = &self.s[tok_start..tok_start + len];
        self.i = tok_start + len;
        self.chars = col - 1 + tok.chars().count();
        Some((col, tok))
    }
}

/// Why a number read as f64 does not fit the f32 every scene number becomes: beyond f32's
/// range it would become infinite (and be refused as "not finite" or "not positive", which it
/// was not), too small it would round to 0. None when it fits (or is not finite: the caller
/// says what it expects then).
pub fn f32_fault(v: f64) -> Option<String> {
    if v.is_finite() && v.abs() > f32::MAX as f64 {
        Some(format!(
            "{v:e} is out of range: numbers are 32-bit floats, at most about 3.4e38"
        ))
    } else if v != 0.0 && v as f32 == 0.0 {
        Some(format!(
            "{v:e} is too small: numbers are 32-bit floats, and it would round to 0"
        ))
    } else {
        None
    }
}

#[cfg(test)]
mod tests {
    use super::Fields;

    #[test]
    fn columns_count_characters() {
        let f: Vec<_> = Fields::new("  é 1/2  ü\tx").collect();
        assert_eq!(f, vec![(3, "é"), (5, "1/2"), (10, "ü"), (12, "x")]);
    }
}
