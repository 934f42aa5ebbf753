//! The image scaled to the page's display (issue 19), as a scanner's scan
//! converter writes its frame at the monitor's resolution.
//!
//! The imaging thread renders 512 × 864 pixels (the grid that carries the
//! axial resolution, issue 21); a 1280 × 800 page draws the image in a box
//! of ~230 × 350 device pixels, so ~80 % of the pixels sent were thrown away
//! by the browser's own downscale after costing bytes, the byte budget's
//! image rate (~8 images/s of ~43 KB at 400 KB/s) and the page's JPEG
//! decoding. The page tells the server the box it draws the image in
//! ([`crate::protocol::ViewerCommand::ImageSize`]); each frame is reduced to
//! fit it, its pixels' aspect kept (never enlarged: a larger box gets the
//! rendered frame as it is).
//!
//! Filters: the gray levels through a triangle filter stretched to the
//! reduction (each output pixel a tent-weighted mean of the input pixels
//! under its footprint: no aliasing of the speckle, and no ringing beside a
//! bright wall, which a Lanczos filter would add); the Doppler overlay's
//! codes by the nearest input pixel, since a mean of two colour codes is no
//! code.

use fast_image_resize::images::{Image, ImageRef};
use fast_image_resize::{FilterType, PixelType, ResizeAlg, ResizeOptions, Resizer};

/// Smallest display box a page may ask for (device pixels a side).
pub const MIN_DISPLAY: u32 = 16;

/// Largest display box a page may ask for (device pixels a side): an 8K
/// monitor's width.
pub const MAX_DISPLAY: u32 = 8192;

/// The size (`width`, `height`) a `width × height` frame is sent at to a
/// page drawing it in a `box_w × box_h` box: scaled by `min(box_w / width,
/// box_h / height, 1)`, each side rounded and at least 1 pixel.
pub fn fitted_size(width: u32, height: u32, box_w: u32, box_h: u32) -> (u32, u32) {
    if width == 0 || height == 0 {
        return (width, height);
    }
    let s = (f64::from(box_w) / f64::from(width))
        .min(f64::from(box_h) / f64::from(height))
        .min(1.0);
    if s >= 1.0 {
        return (width, height);
    }
    let side = |n: u32| ((f64::from(n) * s).round() as u32).clamp(1, n);
    (side(width), side(height))
}

/// One connection's scaler: the page's display box and the scratch of the
/// last reduction (reused from frame to frame).
pub struct DisplayFit {
    /// The box the page draws the image in (device pixels), once told.
    display: Option<(u32, u32)>,
    resizer: Resizer,
    pixels: Vec<u8>,
    overlay: Vec<u8>,
}

impl Default for DisplayFit {
    fn default() -> Self {
        Self {
            display: None,
            resizer: Resizer::new(),
            pixels: Vec::new(),
            overlay: Vec::new(),
        }
    }
}

/// A frame as it is sent: its size and its pixels (and overlay codes,
/// empty when it has none).
pub struct Fitted<'a> {
    /// Columns.
    pub width: u32,
    /// Rows.
    pub height: u32,
    /// 8-bit gray levels, row-major.
    pub pixels: &'a [u8],
    /// Overlay codes, one a pixel, or empty.
    pub overlay: &'a [u8],
}

impl DisplayFit {
    /// Sets the page's display box (device pixels, clamped to
    /// [`MIN_DISPLAY`]..=[`MAX_DISPLAY`]).
    pub fn set_display(&mut self, width: u32, height: u32) {
        let c = |n: u32| n.clamp(MIN_DISPLAY, MAX_DISPLAY);
        self.display = Some((c(width), c(height)));
    }

    /// The frame (`width × height` gray `pixels`, `overlay` codes of the
    /// same size or empty) as it goes to the page: reduced to the display
    /// box when one is set and smaller, else as it is. `None` when the
    /// buffers are shorter than the size says or the scaler refuses.
    pub fn fit<'a>(
        &'a mut self,
        width: u32,
        height: u32,
        pixels: &'a [u8],
        overlay: &'a [u8],
    ) -> Option<Fitted<'a>> {
        let n = width as usize * height as usize;
        if pixels.len() < n || !(overlay.is_empty() || overlay.len() >= n) {
            return None;
        }
        let (w, h) = match self.display {
            Some((bw, bh)) => fitted_size(width, height, bw, bh),
            None => (width, height),
        };
        if (w, h) == (width, height) {
            let overlay = if overlay.is_empty() {
                overlay
            } else {
                &overlay[..n]
            };
            return Some(Fitted {
                width,
                height,
                pixels: &pixels[..n],
                overlay,
            });
        }
        let tent = ResizeOptions::new().resize_alg(ResizeAlg::Convolution(FilterType::Bilinear));
        Self::reduce(
            &mut self.resizer,
            (width, height),
            &pixels[..n],
            (w, h),
            &mut self.pixels,
            &tent,
        )?;
        self.overlay.clear();
        if !overlay.is_empty() {
            let nearest = ResizeOptions::new().resize_alg(ResizeAlg::Nearest);
            Self::reduce(
                &mut self.resizer,
                (width, height),
                &overlay[..n],
                (w, h),
                &mut self.overlay,
                &nearest,
            )?;
        }
        Some(Fitted {
            width: w,
            height: h,
            pixels: &self.pixels,
            overlay: &self.overlay,
        })
    }

    /// Resamples the 8-bit `src` (`from`) into `dst` (`to`) with `options`.
    fn reduce(
        resizer: &mut Resizer,
        from: (u32, u32),
        src: &[u8],
        to: (u32, u32),
        dst: &mut Vec<u8>,
        options: &ResizeOptions,
    ) -> Option<()> {
        dst.resize(to.0 as usize * to.1 as usize, 0);
        let src = ImageRef::new(from.0, from.1, src, PixelType::U8).ok()?;
        let mut out = Image::from_slice_u8(to.0, to.1, dst, PixelType::U8).ok()?;
        resizer
            .resize(&src, &mut out, options)
            .map_err(|e| tracing::error!("reducing an image frame to the display: {e}"))
            .ok()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_frame_fits_the_box_with_its_aspect_and_is_never_enlarged() {
        // 512 × 864 in a 1280 × 800 page's ~232 × 348 box: the height binds
        // (348 / 864 = 0.403 < 232 / 512 = 0.453).
        assert_eq!(fitted_size(512, 864, 232, 348), (206, 348));
        // A box larger than the frame: the frame as it is.
        assert_eq!(fitted_size(512, 864, 2000, 2000), (512, 864));
        // A sliver of a box: at least a pixel a side.
        assert_eq!(fitted_size(512, 864, 1, 1000), (1, 2));
    }

    #[test]
    fn the_gray_levels_keep_their_mean_and_a_code_is_never_mixed() {
        // A vertical ramp 0..=255 and two overlay codes in halves.
        let (w, h) = (64u32, 128u32);
        let px: Vec<u8> = (0..w * h).map(|i| ((i / w) * 2) as u8).collect();
        let codes: Vec<u8> = (0..w * h)
            .map(|i| if i % w < w / 2 { 7 } else { 200 })
            .collect();
        let mut fit = DisplayFit::default();
        fit.set_display(32, 64);
        let f = fit.fit(w, h, &px, &codes).unwrap();
        assert_eq!((f.width, f.height), (32, 64));
        // A tent filter keeps the mean of a ramp to within the rounding of
        // its output (½ level) plus the edge rows' clamping (the filter's
        // half-width, 2 input rows of 2 levels, over 128 rows: ~0.1 level).
        let mean = |v: &[u8]| v.iter().map(|&x| f64::from(x)).sum::<f64>() / v.len() as f64;
        assert!(
            (mean(f.pixels) - mean(&px)).abs() < 0.6,
            "{} vs {}",
            mean(f.pixels),
            mean(&px)
        );
        assert!(f.overlay.iter().all(|&c| c == 7 || c == 200));
        assert_eq!(f.overlay.iter().filter(|&&c| c == 7).count(), 32 * 64 / 2);
    }

    #[test]
    fn without_a_box_or_with_short_buffers_the_frame_goes_as_it_is_or_not_at_all() {
        let px = vec![9u8; 20];
        let mut fit = DisplayFit::default();
        let f = fit.fit(4, 5, &px, &[]).unwrap();
        assert_eq!((f.width, f.height, f.pixels.len()), (4, 5, 20));
        assert!(fit.fit(5, 5, &px, &[]).is_none());
        assert!(fit.fit(4, 5, &px, &[1, 2]).is_none());
    }
}
