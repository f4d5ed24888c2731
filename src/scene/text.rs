//! Reading line-based text formats (OBJ, ASCII PLY): fields with their columns, for errors
//! that point at line:col.

/// Whitespace-separated fields with their 1-based columns.
#[derive(Clone)]
pub struct Fields<'a> {
    s: &'a str,
    i: usize,
}

impl<'a> Fields<'a> {
    pub fn new(s: &'a str) -> Self {
        Fields { s, i: 0 }
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
        self.i = tok_start + len;
        Some((
            self.s[..tok_start].chars().count() + 1,
            &self.s[tok_start..tok_start + len],
        ))
    }
}
