//! Radiance HDR (RGBE) images: Greg Ward's format ("Real Pixels", Graphics Gems II, 1991),
//! as Bruce Walter's reference reader (`rgbe.c`, which Mitsuba's `Bitmap` uses) reads it.
//!
//! - A header of text lines: `#?RADIANCE` (or any `#?` program name), then `NAME=value`
//!   lines and comments up to an empty line. `FORMAT` must be `32-bit_rle_rgbe` if given
//!   (XYZE is refused); `EXPOSURE` and the others are ignored, as Mitsuba ignores them.
//! - The resolution line: only the standard orientation `-Y height +X width` (rows from the
//!   top, pixels left to right), the only one `rgbe.c` accepts.
//! - Scanlines, each either flat (4 bytes a pixel) or, for widths 8 to 32767, "new" run-length
//!   encoded: `2 2 hi lo` (the width), then each of the four channels as runs
//!   (a count above 128 repeats the next byte count − 128 times) and literals (a count of at
//!   most 128 is followed by that many bytes). A scanline that does not start with `2 2`
//!   means the rest of the image is flat, as in `rgbe.c`.
//!
//! A pixel (r, g, b, e) is `(r, g, b) · 2^(e − 136)`, black where e = 0 (`rgbe2float`).
//!
//! Every count is checked against the bytes that are left and the width, and the image's
//! memory against what is free ([`crate::check_allocation`]) before it is allocated: a
//! hostile header or a truncated file gives an error, never a panic or an unbounded
//! allocation.

use crate::Color;

/// The header lines read at most (a real header has a handful).
const MAX_HEADER_LINES: usize = 4096;

/// Whether `bytes` start like a Radiance HDR file.
pub fn is_rgbe(bytes: &[u8]) -> bool {
    bytes.starts_with(b"#?")
}

/// Decodes a Radiance HDR file's bytes: (width, height, linear RGB pixels, top row first).
pub fn decode(bytes: &[u8]) -> Result<(u32, u32, Vec<Color>), String> {
    let mut r = Reader { bytes, pos: 0 };
    let (width, height) = header(&mut r)?;
    let n = width as u64 * height as u64;
    // The pixels, and one scanline of RGBE bytes.
    crate::check_allocation(n * std::mem::size_of::<Color>() as u64 + 4 * width as u64)
        .map_err(|e| format!("a {width}×{height} image {e}"))?;
    let (w, h) = (width as usize, height as usize);
    let mut pixels = Vec::with_capacity(w * h);
    let mut line = vec![[0u8; 4]; w];
    let mut flat = !(8..=0x7fff).contains(&w);
    for y in 0..h {
        if !flat {
            let start = r.peek(4).ok_or_else(|| truncated(y, h))?;
            if start[0] == 2 && start[1] == 2 && start[2] & 0x80 == 0 {
                r.pos += 4;
                let len = (start[2] as usize) << 8 | start[3] as usize;
                if len != w {
                    return Err(format!(
                        "scanline {y} says it is {len} pixels wide, the image is {w}"
                    ));
                }
                rle_scanline(&mut r, &mut line, y, h)?;
            } else {
                flat = true;
            }
        }
        if flat {
            let data = r.take(4 * w).ok_or_else(|| truncated(y, h))?;
            for (px, c) in line.iter_mut().zip(data.chunks_exact(4)) {
                px.copy_from_slice(c);
            }
        }
        pixels.extend(line.iter().map(|&p| rgbe_to_rgb(p)));
    }
    Ok((width, height, pixels))
}

/// `rgbe2float`: (r, g, b) · 2^(e − 128 − 8); black where e = 0.
#[inline]
fn rgbe_to_rgb([r, g, b, e]: [u8; 4]) -> Color {
    if e == 0 {
        return Color::ZERO;
    }
    // 2^(e − 136) for e in 1..=255: from 2^−135 (a subnormal f32, still exact) to 2^119.
    let f = (2.0f64).powi(e as i32 - 136) as f32;
    Color::new(r as f32 * f, g as f32 * f, b as f32 * f)
}

fn truncated(y: usize, h: usize) -> String {
    format!("the file ends in scanline {y} of {h} (truncated)")
}

/// One run-length-encoded scanline's four channels into `line`.
fn rle_scanline(r: &mut Reader, line: &mut [[u8; 4]], y: usize, h: usize) -> Result<(), String> {
    let w = line.len();
    for ch in 0..4 {
        let mut x = 0;
        while x < w {
            let count = r.take(1).ok_or_else(|| truncated(y, h))?[0] as usize;
            let (n, run) = if count > 128 {
                (count - 128, true)
            } else {
                (count, false)
            };
            if n == 0 || n > w - x {
                return Err(format!(
                    "bad run-length data in scanline {y}: a run of {n} at pixel {x} of {w}"
                ));
            }
            if run {
                let v = r.take(1).ok_or_else(|| truncated(y, h))?[0];
                line[x..x + n].iter_mut().for_each(|p| p[ch] = v);
            } else {
                let vs = r.take(n).ok_or_else(|| truncated(y, h))?;
                line[x..x + n]
                    .iter_mut()
                    .zip(vs)
                    .for_each(|(p, &v)| p[ch] = v);
            }
            x += n;
        }
    }
    Ok(())
}

/// The header and the resolution line: (width, height).
fn header(r: &mut Reader) -> Result<(u32, u32), String> {
    let first = r.line().ok_or("the file ends in its header")?;
    if !first.starts_with(b"#?") {
        return Err("not a Radiance HDR file (it must start with '#?')".into());
    }
    let mut lines = 0;
    loop {
        let l = r
            .line()
            .ok_or("the file ends in its header (no empty line)")?;
        if l.is_empty() {
            break;
        }
        lines += 1;
        if lines > MAX_HEADER_LINES {
            return Err(format!("more than {MAX_HEADER_LINES} header lines"));
        }
        if let Some(f) = l.strip_prefix(b"FORMAT=") {
            if f.trim_ascii() != b"32-bit_rle_rgbe" {
                return Err(format!(
                    "FORMAT '{}' is not supported (only 32-bit_rle_rgbe)",
                    crate::input::shorten(&String::from_utf8_lossy(f))
                ));
            }
        }
    }
    let res = r.line().ok_or("the file ends before its resolution line")?;
    let text = String::from_utf8_lossy(res);
    let bad = || {
        format!(
            "resolution line '{}': expected '-Y height +X width' (the only orientation \
             supported)",
            crate::input::shorten(&text)
        )
    };
    let parts: Vec<&str> = text.split_ascii_whitespace().collect();
    let [a, hs, b, ws] = parts[..] else {
        return Err(bad());
    };
    if a != "-Y" || b != "+X" {
        return Err(bad());
    }
    let (Ok(h), Ok(w)) = (hs.parse::<u32>(), ws.parse::<u32>()) else {
        return Err(bad());
    };
    let most = crate::limits::MAX_SIZE as u32;
    if w == 0 || h == 0 || w > most || h > most {
        return Err(format!(
            "the image is {w}×{h} pixels; each side must be 1 to {most}"
        ));
    }
    Ok((w, h))
}

/// A cursor over the file's bytes; every read is bounds-checked.
struct Reader<'a> {
    bytes: &'a [u8],
    pos: usize,
}

impl<'a> Reader<'a> {
    fn peek(&self, n: usize) -> Option<&'a [u8]> {
        self.bytes.get(self.pos..self.pos.checked_add(n)?)
    }

    fn take(&mut self, n: usize) -> Option<&'a [u8]> {
        let s = self.peek(n)?;
        self.pos += n;
        Some(s)
    }

    /// The next line without its '\n'; None at the end of the file.
    fn line(&mut self) -> Option<&'a [u8]> {
        let rest = self.bytes.get(self.pos..)?;
        let end = rest.iter().position(|&b| b == b'\n')?;
        self.pos += end + 1;
        Some(&rest[..end])
    }
}

/// Encodes an image as a Radiance HDR file (for tests and the tools that make test images):
/// run-length encoded scanlines where the width allows, else flat.
pub fn encode(width: u32, height: u32, pixels: &[Color]) -> Vec<u8> {
    let mut out =
        format!("#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y {height} +X {width}\n").into_bytes();
    let w = width as usize;
    for row in pixels.chunks_exact(w.max(1)) {
        let rgbe: Vec<[u8; 4]> = row.iter().map(|&c| rgb_to_rgbe(c)).collect();
        if !(8..=0x7fff).contains(&w) {
            rgbe.iter().for_each(|p| out.extend_from_slice(p));
            continue;
        }
        out.extend_from_slice(&[2, 2, (w >> 8) as u8, w as u8]);
        for ch in 0..4 {
            let vals: Vec<u8> = rgbe.iter().map(|p| p[ch]).collect();
            encode_channel(&vals, &mut out);
        }
    }
    out
}

/// `float2rgbe`: the largest channel's exponent, the mantissas scaled to 0..255.
fn rgb_to_rgbe(c: Color) -> [u8; 4] {
    let v = c.max_element();
    if !(v >= 1e-32) {
        return [0; 4];
    }
    // v = m · 2^e with m in [0.5, 1).
    let e = v.log2().floor() as i32 + 1;
    let scale = (2.0f64).powi(-e) * 256.0;
    let q = |x: f32| ((x as f64 * scale) as u32).min(255) as u8;
    [q(c.x), q(c.y), q(c.z), (e + 128).clamp(0, 255) as u8]
}

/// One channel of a scanline as runs (of 3 or more equal bytes) and literals, each at
/// most 127 long.
fn encode_channel(v: &[u8], out: &mut Vec<u8>) {
    let mut i = 0;
    while i < v.len() {
        let run = v[i..].iter().take(127).take_while(|&&b| b == v[i]).count();
        if run >= 3 {
            out.extend_from_slice(&[128 + run as u8, v[i]]);
            i += run;
            continue;
        }
        // Literals up to the next run of three.
        let mut j = i;
        while j < v.len() && j - i < 127 {
            if j + 2 < v.len() && v[j] == v[j + 1] && v[j] == v[j + 2] {
                break;
            }
            j += 1;
        }
        out.push((j - i) as u8);
        out.extend_from_slice(&v[i..j]);
        i = j;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn image(w: u32, h: u32) -> Vec<Color> {
        (0..w * h)
            .map(|i| {
                let (x, y) = ((i % w) as f32, (i / w) as f32);
                // Runs (constant rows' blue), literals and a wide range of exponents.
                Color::new(
                    0.25 * x + 0.01,
                    (y + 1.0) * 37.0,
                    if x < 5.0 { 2.0 } else { 0.0 },
                )
            })
            .collect()
    }

    /// What `encode` writes, `decode` reads back, within RGBE's 8-bit mantissas; flat and
    /// run-length encoded widths both.
    #[test]
    fn round_trip() {
        for (w, h) in [(3, 2), (16, 5), (200, 3)] {
            let px = image(w, h);
            let bytes = encode(w, h, &px);
            let (dw, dh, back) = decode(&bytes).unwrap();
            assert_eq!((dw, dh), (w, h));
            for (a, b) in px.iter().zip(&back) {
                let tol = a.max_element() / 128.0;
                assert!((*a - *b).abs().max_element() <= tol, "{a} {b}");
            }
        }
    }

    /// `rgbe2float` on known bytes: mantissa · 2^(e − 136).
    #[test]
    fn pixel_values() {
        assert_eq!(rgbe_to_rgb([128, 64, 0, 129]), Color::new(1.0, 0.5, 0.0));
        assert_eq!(rgbe_to_rgb([255, 255, 255, 0]), Color::ZERO);
        assert!(rgbe_to_rgb([255, 255, 255, 255]).is_finite());
    }

    #[test]
    fn bad_files_are_refused() {
        let good = encode(16, 4, &image(16, 4));
        let err = |b: &[u8]| decode(b).unwrap_err();
        assert!(
            err(b"#?RADIANCE\nFORMAT=32-bit_rle_xyze\n\n-Y 1 +X 1\n\0\0\0\0").contains("FORMAT")
        );
        assert!(err(b"#?RADIANCE\n\n+Y 1 +X 1\n\0\0\0\0").contains("orientation"));
        assert!(err(b"#?RADIANCE\n\n-Y 0 +X 1\n").contains("each side"));
        assert!(err(b"#?RADIANCE\n\n-Y 4000000 +X 1\n").contains("each side"));
        assert!(err(b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n").contains("header"));
        assert!(err(b"#?RADIANCE\n\n-Y 1 +X 1\n\0\0").contains("truncated"));
        // Every prefix of a good file is an error, none a panic.
        for n in 0..good.len() {
            assert!(decode(&good[..n]).is_err(), "{n}");
        }
        // A run longer than the scanline.
        let mut bad = good.clone();
        let at = bad.len() - 3 * 4; // within the last scanline's data
        bad[at] = 200;
        bad.truncate(at + 2);
        assert!(decode(&bad).is_err());
        // A scanline that claims another width.
        let start = good.windows(4).position(|w| w == [2, 2, 0, 16]).unwrap();
        let mut bad = good.clone();
        bad[start + 3] = 17;
        assert!(err(&bad).contains("wide"));
    }
}
