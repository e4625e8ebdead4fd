//! Heat maps of an ensemble over a grid of two varied fields, as PNG (`svi ensemble --plot
//! FILE.png`): one square of colour per member, the first field across and the second up.
//!
//! The PNG is written here, without an image library: 8-bit indexed colour (a palette of 256
//! colours: 255 steps of the colour map and dark grey for members without a value) in stored
//! (uncompressed) deflate blocks — a valid PNG any viewer opens, at one byte per pixel.

use std::io::{self, Write};

/// A grid of values to draw.
#[derive(Debug, Clone, Copy)]
pub struct Heatmap<'a> {
    /// Cells across (values of the first field).
    pub columns: usize,
    /// Cells up (values of the second field).
    pub rows: usize,
    /// The value of cell (i, j) at `i·rows + j` (`None`: no value, drawn dark grey).
    pub values: &'a [Option<f64>],
    /// Colour cyclically with period 2π (angles), else from the smallest to the largest
    /// value on a perceptual blue–green–yellow map.
    pub cyclic: bool,
}

/// The smallest width and height of the picture in pixels: small grids get larger squares.
const MIN_PIXELS: usize = 400;

/// Write `map` as a PNG image.
pub fn write_png(map: &Heatmap<'_>, out: &mut impl Write) -> io::Result<()> {
    if map.columns == 0 || map.rows == 0 || map.values.len() != map.columns * map.rows {
        return Err(io::Error::other(format!(
            "a {} × {} heat map needs {} values, not {}",
            map.columns,
            map.rows,
            map.columns * map.rows,
            map.values.len()
        )));
    }
    let scale = (MIN_PIXELS / map.columns.max(map.rows)).max(1);
    let (width, height) = (map.columns * scale, map.rows * scale);
    let finite = map.values.iter().flatten().filter(|x| x.is_finite());
    let (low, high) = finite.fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), x| {
        (l.min(*x), h.max(*x))
    });
    let index = |value: Option<f64>| -> u8 {
        match value.filter(|x| x.is_finite()) {
            None => 0,
            Some(x) => {
                let fraction = if map.cyclic {
                    (x / std::f64::consts::TAU).rem_euclid(1.0)
                } else if high > low {
                    (x - low) / (high - low)
                } else {
                    0.5
                };
                1 + (fraction * 254.0).round().clamp(0.0, 254.0) as u8
            }
        }
    };
    // Scanlines top to bottom: the top row is the largest value of the second field.
    let mut pixels = Vec::with_capacity(height * (width + 1));
    for y in 0..height {
        let j = map.rows - 1 - y / scale;
        pixels.push(0); // filter type: none
        for x in 0..width {
            let i = x / scale;
            pixels.push(index(map.values[i * map.rows + j]));
        }
    }
    let mut palette = Vec::with_capacity(256 * 3);
    palette.extend_from_slice(&[40, 40, 40]);
    for k in 0..255 {
        let t = k as f64 / 254.0;
        let rgb = if map.cyclic { hue(t) } else { viridis(t) };
        palette.extend_from_slice(&rgb);
    }
    out.write_all(b"\x89PNG\r\n\x1a\n")?;
    let mut header = Vec::with_capacity(13);
    header.extend_from_slice(&(width as u32).to_be_bytes());
    header.extend_from_slice(&(height as u32).to_be_bytes());
    header.extend_from_slice(&[8, 3, 0, 0, 0]);
    chunk(out, b"IHDR", &header)?;
    chunk(out, b"PLTE", &palette)?;
    chunk(out, b"IDAT", &zlib_stored(&pixels))?;
    chunk(out, b"IEND", &[])
}

/// A colour of a perceptual blue–green–yellow map (viridis, by its key colours), `t` in [0, 1].
fn viridis(t: f64) -> [u8; 3] {
    const KEYS: [[f64; 3]; 6] = [
        [68.0, 1.0, 84.0],
        [65.0, 68.0, 135.0],
        [42.0, 120.0, 142.0],
        [34.0, 168.0, 132.0],
        [122.0, 209.0, 81.0],
        [253.0, 231.0, 37.0],
    ];
    let position = t.clamp(0.0, 1.0) * (KEYS.len() - 1) as f64;
    let k = (position.floor() as usize).min(KEYS.len() - 2);
    let f = position - k as f64;
    let channel = |c: usize| (KEYS[k][c] + f * (KEYS[k + 1][c] - KEYS[k][c])).round() as u8;
    [channel(0), channel(1), channel(2)]
}

/// A colour of a cyclic hue wheel, `t` in [0, 1) (0 and 1 the same colour).
fn hue(t: f64) -> [u8; 3] {
    let (saturation, value) = (0.75, 0.95);
    let h = t.rem_euclid(1.0) * 6.0;
    let c = value * saturation;
    let x = c * (1.0 - ((h % 2.0) - 1.0).abs());
    let (r, g, b) = match h as usize {
        0 => (c, x, 0.0),
        1 => (x, c, 0.0),
        2 => (0.0, c, x),
        3 => (0.0, x, c),
        4 => (x, 0.0, c),
        _ => (c, 0.0, x),
    };
    let m = value - c;
    let byte = |v: f64| ((v + m) * 255.0).round() as u8;
    [byte(r), byte(g), byte(b)]
}

/// Write one PNG chunk: length, type, data, CRC-32 of type and data.
fn chunk(out: &mut impl Write, kind: &[u8; 4], data: &[u8]) -> io::Result<()> {
    out.write_all(&(data.len() as u32).to_be_bytes())?;
    out.write_all(kind)?;
    out.write_all(data)?;
    let crc = crc32(kind.iter().chain(data));
    out.write_all(&crc.to_be_bytes())
}

/// CRC-32 (ISO 3309, as PNG uses it).
fn crc32<'a>(bytes: impl Iterator<Item = &'a u8>) -> u32 {
    let mut crc = 0xffff_ffffu32;
    for &byte in bytes {
        crc ^= u32::from(byte);
        for _ in 0..8 {
            crc = if crc & 1 == 1 {
                0xedb8_8320 ^ (crc >> 1)
            } else {
                crc >> 1
            };
        }
    }
    !crc
}

/// A zlib stream of `data` in stored deflate blocks, with its Adler-32 checksum.
fn zlib_stored(data: &[u8]) -> Vec<u8> {
    let mut out = vec![0x78, 0x01];
    let blocks: Vec<&[u8]> = data.chunks(65_535).collect();
    if blocks.is_empty() {
        out.extend_from_slice(&[1, 0, 0, 0xff, 0xff]);
    }
    for (k, block) in blocks.iter().enumerate() {
        out.push(u8::from(k + 1 == blocks.len()));
        let length = block.len() as u16;
        out.extend_from_slice(&length.to_le_bytes());
        out.extend_from_slice(&(!length).to_le_bytes());
        out.extend_from_slice(block);
    }
    let (mut a, mut b) = (1u32, 0u32);
    for &byte in data {
        a = (a + u32::from(byte)) % 65_521;
        b = (b + a) % 65_521;
    }
    out.extend_from_slice(&((b << 16) | a).to_be_bytes());
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn checksums_match_their_reference_values() {
        // The CRC-32 of "123456789" is the standard check value.
        assert_eq!(crc32(b"123456789".iter()), 0xcbf4_3926);
        let stream = zlib_stored(b"Wikipedia");
        // Adler-32 of "Wikipedia" (the example of its definition).
        assert_eq!(&stream[stream.len() - 4..], &0x11e6_0398u32.to_be_bytes());
    }

    #[test]
    fn a_heat_map_is_a_png_of_the_grid() {
        let values = [Some(0.0), Some(1.0), None, Some(2.0), Some(3.0), Some(4.0)];
        let map = Heatmap {
            columns: 3,
            rows: 2,
            values: &values,
            cyclic: false,
        };
        let mut png = Vec::new();
        write_png(&map, &mut png).unwrap();
        assert_eq!(&png[..8], b"\x89PNG\r\n\x1a\n");
        // 400 / 3 = 133 pixels per cell: 399 × 266.
        assert_eq!(&png[16..24], &[0, 0, 1, 143, 0, 0, 1, 10]);
        assert!(png.ends_with(b"IEND\xae\x42\x60\x82"));
        let wrong = Heatmap { rows: 3, ..map };
        assert!(write_png(&wrong, &mut Vec::new()).is_err());
        assert_eq!(viridis(0.0), [68, 1, 84]);
        assert_eq!(viridis(1.0), [253, 231, 37]);
        assert_eq!(hue(0.0), hue(1.0));
    }
}
