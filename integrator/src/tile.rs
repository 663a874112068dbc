//! Square image tiles: the unit of work that integrators hand to rayon.

use pathwave_engine::render_scene::PixelWindow;

/// Tile edge in pixels.
pub const TILE: u32 = 16;

/// A rectangle of the image.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Tile {
    /// Left column.
    pub x0: u32,
    /// Top row.
    pub y0: u32,
    /// Width (smaller than [`TILE`] at the right edge).
    pub w: u32,
    /// Height (smaller than [`TILE`] at the bottom edge).
    pub h: u32,
}

impl Tile {
    /// Number of tiles across and down an image.
    pub fn grid(width: u32, height: u32) -> (u32, u32) {
        (width.div_ceil(TILE), height.div_ceil(TILE))
    }

    /// Tile `t` (row-major) of an image `width` x `height`.
    pub fn new(t: u32, width: u32, height: u32) -> Self {
        let tiles_x = width.div_ceil(TILE);
        let (x0, y0) = ((t % tiles_x) * TILE, (t / tiles_x) * TILE);
        Self { x0, y0, w: (x0 + TILE).min(width) - x0, h: (y0 + TILE).min(height) - y0 }
    }

    /// Number of tiles across and down a window of the image.
    pub fn grid_of(window: &PixelWindow) -> (u32, u32) {
        Self::grid(window.w, window.h)
    }

    /// Tile `t` (row-major) of a window of the image, in image coordinates.
    pub fn in_window(t: u32, window: &PixelWindow) -> Self {
        let tile = Self::new(t, window.w, window.h);
        Self { x0: window.x0 + tile.x0, y0: window.y0 + tile.y0, ..tile }
    }

    /// Image coordinates of pixel `i` (row-major within the tile).
    pub fn pixel(&self, i: u32) -> (u32, u32) {
        (self.x0 + i % self.w, self.y0 + i / self.w)
    }

    /// Number of pixels.
    pub fn len(&self) -> u32 {
        self.w * self.h
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tiles_cover_every_pixel_once() {
        let (w, h) = (37, 21);
        let (tx, ty) = Tile::grid(w, h);
        let mut seen = vec![0; (w * h) as usize];
        for t in 0..tx * ty {
            let tile = Tile::new(t, w, h);
            for i in 0..tile.len() {
                let (x, y) = tile.pixel(i);
                seen[(y * w + x) as usize] += 1;
            }
        }
        assert!(seen.iter().all(|&c| c == 1));
    }
}
