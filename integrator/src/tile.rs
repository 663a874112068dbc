//! Square image tiles: the unit of work that integrators hand to rayon, and the one fan-out
//! over them that both integrators use ([`render_tiles`]).

use pathwave_engine::render_scene::PixelWindow;
use rayon::prelude::*;
use std::sync::atomic::{AtomicUsize, Ordering};

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

    /// Number of pixels (a tile is never empty).
    #[allow(clippy::len_without_is_empty)]
    pub fn len(&self) -> u32 {
        self.w * self.h
    }

    /// Each pixel's index in the tile (row-major) and in `window` (which holds the tile).
    pub fn window_indices(&self, window: &PixelWindow) -> impl Iterator<Item = (usize, usize)> {
        (0..self.len()).map(move |i| {
            let (x, y) = self.pixel(i);
            (i as usize, window.index(x, y))
        })
    }
}

/// Renders every tile of `window` on rayon's threads: `render(state, tile)` with a `state`
/// made by `init` once per worker (the wavefront's path slots and queues), `progress(done,
/// total)` after each tile from any thread. The results come back in tile order, whatever
/// order the tiles ran in.
pub fn render_tiles<S, T: Send>(
    window: &PixelWindow,
    progress: &(dyn Fn(usize, usize) + Sync),
    init: impl Fn() -> S + Sync + Send,
    render: impl Fn(&mut S, &Tile) -> T + Sync + Send,
) -> Vec<(Tile, T)> {
    let (tx, ty) = Tile::grid_of(window);
    let total = (tx * ty) as usize;
    let done = AtomicUsize::new(0);
    (0..tx * ty)
        .into_par_iter()
        .map_init(init, |state, t| {
            let tile = Tile::in_window(t, window);
            let out = render(state, &tile);
            progress(done.fetch_add(1, Ordering::Relaxed) + 1, total);
            (tile, out)
        })
        .collect()
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

    #[test]
    fn render_tiles_returns_every_tile_of_a_window_in_order_and_reports_each() {
        let window = PixelWindow { x0: 5, y0: 3, w: 37, h: 21 };
        let reports = std::sync::Mutex::new(Vec::new());
        let tiles = render_tiles(
            &window,
            &|done, total| reports.lock().unwrap().push((done, total)),
            || 0u32,
            |calls, tile| {
                *calls += 1;
                tile.window_indices(&window).map(|(_, k)| k).collect::<Vec<_>>()
            },
        );
        let mut seen = vec![0; window.len()];
        for (t, (tile, indices)) in tiles.iter().enumerate() {
            assert_eq!(*tile, Tile::in_window(t as u32, &window));
            indices.iter().for_each(|&k| seen[k] += 1);
        }
        assert!(seen.iter().all(|&c| c == 1), "every pixel of the window once");
        let mut reports = reports.into_inner().unwrap();
        reports.sort();
        assert_eq!(reports, (1..=tiles.len()).map(|d| (d, tiles.len())).collect::<Vec<_>>());
    }
}
