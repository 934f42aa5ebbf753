//! PNG output of frames (contact sheets with their labels are drawn by
//! `echothigh_experiments::sheet`, with plotters).

use crate::error::ImagingError;
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

#[cfg(test)]
mod tests {
    use super::*;

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
