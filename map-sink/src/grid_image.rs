//! The occupancy grid as an image: trinary pixels, the first row the map's largest y (image
//! rows run downwards, the map's y upwards; map_server flips the rows back on reading).

use crate::error::SinkError;
use back_end::occupancy_grid::OccupancyGrid;
use saved_map::trinary_pixel;

/// The grid's trinary pixels, row by row from the top of the image.
pub fn grid_pixels(grid: &OccupancyGrid) -> Vec<u8> {
    let (width, height) = (grid.width(), grid.height());
    let mut pixels = Vec::with_capacity(width * height);
    for row in (0..height).rev() {
        pixels.extend((0..width).map(|col| trinary_pixel(grid.state(col, row))));
    }
    pixels
}

/// An 8-bit greyscale PNG of `pixels` (rows from the top), for people: every image viewer
/// and browser shows PNG, few show PGM.
pub fn encode_png(width: usize, height: usize, pixels: &[u8]) -> Result<Vec<u8>, SinkError> {
    let fail = |e: png::EncodingError| SinkError::Png(e.to_string());
    let size =
        |n: usize| u32::try_from(n).map_err(|_| SinkError::Png(format!("{n} pixels across")));
    let mut bytes = Vec::new();
    let mut encoder = png::Encoder::new(&mut bytes, size(width)?, size(height)?);
    encoder.set_color(png::ColorType::Grayscale);
    encoder.set_depth(png::BitDepth::Eight);
    let mut writer = encoder.write_header().map_err(fail)?;
    writer.write_image_data(pixels).map_err(fail)?;
    writer.finish().map_err(fail)?;
    Ok(bytes)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_png_decodes_to_the_same_pixels() -> Result<(), Box<dyn std::error::Error>> {
        let pixels = [0, 254, 205, 205, 254, 0];
        let bytes = encode_png(3, 2, &pixels)?;
        let mut reader = png::Decoder::new(std::io::Cursor::new(bytes)).read_info()?;
        let mut out = vec![0; reader.output_buffer_size().ok_or("no size")?];
        let info = reader.next_frame(&mut out)?;
        assert_eq!((info.width, info.height), (3, 2));
        assert_eq!(info.color_type, png::ColorType::Grayscale);
        assert_eq!(&out[..info.buffer_size()], pixels);
        Ok(())
    }
}
