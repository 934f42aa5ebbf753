//! PNG output of frames and contact sheets (a grid of frames with row and
//! column labels, so that a person sees the vein states side by side).

use crate::error::ImagingError;
use crate::font::{draw_text, text_width, GLYPH_H};
use std::io::BufWriter;
use std::path::Path;

/// Writes an 8-bit grayscale image (`width · height` bytes, row-major) as PNG.
pub fn write_gray_png(
    path: &Path,
    width: usize,
    height: usize,
    data: &[u8],
) -> Result<(), ImagingError> {
    let err = |message: String| ImagingError::Png {
        path: path.display().to_string(),
        message,
    };
    if width == 0 || height == 0 || data.len() != width * height {
        return Err(err(format!(
            "{} bytes for a {width} x {height} image",
            data.len()
        )));
    }
    let file = std::fs::File::create(path).map_err(|e| err(e.to_string()))?;
    let mut enc = png::Encoder::new(BufWriter::new(file), width as u32, height as u32);
    enc.set_color(png::ColorType::Grayscale);
    enc.set_depth(png::BitDepth::Eight);
    let mut w = enc.write_header().map_err(|e| err(e.to_string()))?;
    w.write_image_data(data).map_err(|e| err(e.to_string()))?;
    w.finish().map_err(|e| err(e.to_string()))
}

/// A composed contact sheet.
#[derive(Debug, Clone, PartialEq)]
pub struct ContactSheet {
    /// Width (pixels).
    pub width: usize,
    /// Height (pixels).
    pub height: usize,
    /// 8-bit grayscale pixels, row-major.
    pub pixels: Vec<u8>,
}

/// Lays out `frames` (row-major grid of `row_labels.len()` rows ×
/// `column_labels.len()` columns, each `frame_width × frame_height` bytes)
/// on a dark background with gaps, the column labels above and the row
/// labels on the left, in a 5 × 7 bitmap font at twice its size.
pub fn contact_sheet(
    frames: &[&[u8]],
    frame_width: usize,
    frame_height: usize,
    row_labels: &[&str],
    column_labels: &[&str],
) -> Result<ContactSheet, ImagingError> {
    let (nr, nc) = (row_labels.len(), column_labels.len());
    if nr == 0
        || nc == 0
        || frames.len() != nr * nc
        || frames.iter().any(|f| f.len() != frame_width * frame_height)
    {
        return Err(ImagingError::Input {
            field: "contact_sheet.frames",
            reason: "need rows x columns frames of frame_width x frame_height bytes",
        });
    }
    let scale = 2;
    let gap = 8;
    let left = row_labels
        .iter()
        .map(|l| text_width(l, scale))
        .max()
        .unwrap_or(0)
        + 2 * gap;
    let top = GLYPH_H * scale + 2 * gap;
    let width = left + nc * (frame_width + gap);
    let height = top + nr * (frame_height + gap);
    let mut pixels = vec![24u8; width * height];
    for (c, label) in column_labels.iter().enumerate() {
        let x = left
            + c * (frame_width + gap)
            + frame_width.saturating_sub(text_width(label, scale)) / 2;
        draw_text(&mut pixels, width, x, gap, label, scale, 255);
    }
    for (r, label) in row_labels.iter().enumerate() {
        let y = top + r * (frame_height + gap) + frame_height.saturating_sub(GLYPH_H * scale) / 2;
        draw_text(&mut pixels, width, gap, y, label, scale, 255);
        for c in 0..nc {
            let f = frames[r * nc + c];
            let (x0, y0) = (
                left + c * (frame_width + gap),
                top + r * (frame_height + gap),
            );
            for (i, row) in f.chunks(frame_width).enumerate() {
                let start = (y0 + i) * width + x0;
                pixels[start..start + frame_width].copy_from_slice(row);
            }
        }
    }
    Ok(ContactSheet {
        width,
        height,
        pixels,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sheet_places_frames_and_labels() {
        let a = vec![100u8; 20 * 10];
        let b = vec![200u8; 20 * 10];
        let s = contact_sheet(&[&a, &b], 20, 10, &["ROW"], &["0 N", "5 N"]).unwrap();
        assert_eq!(s.pixels.len(), s.width * s.height);
        assert!(s.pixels.contains(&255), "labels drawn");
        assert_eq!(s.pixels.iter().filter(|&&p| p == 100).count(), 200);
        assert_eq!(s.pixels.iter().filter(|&&p| p == 200).count(), 200);
        assert!(contact_sheet(&[&a], 20, 10, &["ROW"], &["0 N", "5 N"]).is_err());
    }

    #[test]
    fn png_round_trip() {
        let dir =
            std::env::temp_dir().join(format!("echothigh-imaging-png-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("f.png");
        let data: Vec<u8> = (0..12 * 7).map(|i| (i * 3) as u8).collect();
        write_gray_png(&path, 12, 7, &data).unwrap();
        let dec = png::Decoder::new(std::fs::File::open(&path).unwrap());
        let mut r = dec.read_info().unwrap();
        let mut buf = vec![0; r.output_buffer_size()];
        let info = r.next_frame(&mut buf).unwrap();
        assert_eq!((info.width, info.height), (12, 7));
        assert_eq!(&buf[..info.buffer_size()], &data[..]);
        assert!(write_gray_png(&path, 5, 5, &data).is_err());
        std::fs::remove_dir_all(&dir).ok();
    }
}
