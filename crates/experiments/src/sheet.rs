//! Contact sheets: a grid of grayscale frames (B-mode images) with column
//! labels above and row labels on the left, so that a person sees the vein
//! states side by side. Text is drawn by plotters with the embedded DejaVu
//! Sans ([`crate::plot`]), so no system font is needed.

use anyhow::{ensure, Context, Result};
use plotters::prelude::*;

/// Label height (pixels).
const LABEL_PX: u32 = 16;
/// Gap between frames and around the labels (pixels).
const GAP: usize = 8;
/// Background gray level.
const BACKGROUND: u8 = 24;

/// A composed contact sheet.
#[derive(Debug, Clone, PartialEq)]
pub struct ContactSheet {
    /// Width (pixels).
    pub width: usize,
    /// Height (pixels).
    pub height: usize,
    /// 8-bit grayscale pixels, row-major.
    pub pixels: Vec<u8>,
    /// Top-left corner `(x, y)` (pixels) of each frame, in the order given.
    pub frame_origins: Vec<(usize, usize)>,
}

/// Lays out `frames` (row-major grid of `row_labels.len()` rows ×
/// `column_labels.len()` columns, each `frame_width × frame_height` bytes)
/// on a dark background with gaps, the column labels above and the row
/// labels on the left in white.
pub fn contact_sheet(
    frames: &[&[u8]],
    frame_width: usize,
    frame_height: usize,
    row_labels: &[&str],
    column_labels: &[&str],
) -> Result<ContactSheet> {
    let (nr, nc) = (row_labels.len(), column_labels.len());
    ensure!(
        nr > 0 && nc > 0 && frame_width > 0 && frame_height > 0,
        "contact sheet: need at least one row, one column and non-empty frames"
    );
    ensure!(
        frames.len() == nr * nc && frames.iter().all(|f| f.len() == frame_width * frame_height),
        "contact sheet: need {nr} x {nc} frames of {frame_width} x {frame_height} bytes, got {} frames",
        frames.len()
    );
    crate::plot::register_font();
    let font = ("sans-serif", LABEL_PX).into_font();
    let size = |text: &str| -> Result<(usize, usize)> {
        let (w, h) = font
            .box_size(text)
            .map_err(|e| anyhow::anyhow!("measuring label {text:?}: {e:?}"))?;
        Ok((w as usize, h as usize))
    };
    let mut left = 0;
    for label in row_labels {
        left = left.max(size(label)?.0);
    }
    let left = left + 2 * GAP;
    let top = LABEL_PX as usize + 2 * GAP;
    let width = left + nc * (frame_width + GAP);
    let height = top + nr * (frame_height + GAP);
    let mut rgb = vec![BACKGROUND; 3 * width * height];
    let mut frame_origins = Vec::with_capacity(frames.len());
    for (k, frame) in frames.iter().enumerate() {
        let (x0, y0) = (
            left + (k % nc) * (frame_width + GAP),
            top + (k / nc) * (frame_height + GAP),
        );
        frame_origins.push((x0, y0));
        for (i, row) in frame.chunks(frame_width).enumerate() {
            let start = 3 * ((y0 + i) * width + x0);
            for (px, &g) in rgb[start..start + 3 * frame_width].chunks_mut(3).zip(row) {
                px.fill(g);
            }
        }
    }
    {
        let root =
            BitMapBackend::with_buffer(&mut rgb, (width as u32, height as u32)).into_drawing_area();
        let style = font.color(&WHITE);
        let draw = |text: &str, x: usize, y: usize| {
            root.draw_text(text, &style, (x as i32, y as i32))
                .map_err(|e| anyhow::anyhow!("drawing label {text:?}: {e:?}"))
        };
        for (c, label) in column_labels.iter().enumerate() {
            let x = left + c * (frame_width + GAP) + frame_width.saturating_sub(size(label)?.0) / 2;
            draw(label, x, GAP)?;
        }
        for (r, label) in row_labels.iter().enumerate() {
            let y =
                top + r * (frame_height + GAP) + frame_height.saturating_sub(LABEL_PX as usize) / 2;
            draw(label, GAP, y)?;
        }
        root.present().context("drawing the contact sheet")?;
    }
    // Everything drawn is gray (frames, background, white text blended on
    // gray), so one channel is the image.
    let pixels = rgb.chunks(3).map(|p| p[0]).collect();
    Ok(ContactSheet {
        width,
        height,
        pixels,
        frame_origins,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Frames land unchanged at their origins, and the labels are drawn
    /// with the embedded font: white ink (≥ 200) in the label bands, where
    /// only the background (24) would be without text.
    #[test]
    fn sheet_places_frames_and_draws_labels() {
        let (w, h) = (40, 30);
        let a = vec![100u8; w * h];
        let b: Vec<u8> = (0..w * h).map(|i| (i % 251) as u8).collect();
        let s = contact_sheet(&[&a, &b], w, h, &["healthy"], &["0 N", "5 N"]).unwrap();
        assert_eq!(s.pixels.len(), s.width * s.height);
        for (frame, &(x0, y0)) in [&a, &b].iter().zip(&s.frame_origins) {
            for i in 0..h {
                let row = &s.pixels[(y0 + i) * s.width + x0..][..w];
                assert_eq!(row, &frame[i * w..(i + 1) * w]);
            }
        }
        let (x0, y0) = s.frame_origins[0];
        let above = &s.pixels[..y0 * s.width];
        assert!(
            above.iter().filter(|&&p| p >= 200).count() > 20,
            "no column label ink"
        );
        let beside: Vec<u8> = (y0..y0 + h)
            .flat_map(|y| s.pixels[y * s.width..y * s.width + x0].to_vec())
            .collect();
        assert!(
            beside.iter().filter(|&&p| p >= 200).count() > 20,
            "no row label ink"
        );
        assert!(contact_sheet(&[&a], w, h, &["healthy"], &["0 N", "5 N"]).is_err());
    }
}
