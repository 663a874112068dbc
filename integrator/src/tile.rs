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
    #[expect(clippy::len_without_is_empty, reason = "a tile is never empty")]
    pub fn len(&self) -> u32 {
        self.w * self.h
    }

    /// Each pixel's index in the tile (row-major) and in `window`, for the tile's pixels in
    /// `window` (all of them, but for the tiles of a splatted render's margin).
    pub fn window_indices(&self, window: &PixelWindow) -> impl Iterator<Item = (usize, usize)> {
        (0..self.len()).filter_map(move |i| {
            let (x, y) = self.pixel(i);
            window.contains(x, y).then(|| (i as usize, window.index(x, y)))
        })
    }

    /// The tile grown by `margin` pixels on every side, within `window`.
    pub fn reach(&self, margin: u32, window: &PixelWindow) -> PixelWindow {
        let own = PixelWindow { x0: self.x0, y0: self.y0, w: self.w, h: self.h };
        own.grown(margin, u32::MAX, u32::MAX).meet(window)
    }
}

/// One tile's pixels in an image-sized buffer of the window (row-major): a slice per row of
/// the tile, disjoint from every other tile's.
pub struct TileRows<'f, P> {
    rows: Vec<&'f mut [P]>,
}

impl<P> TileRows<'_, P> {
    /// Sets pixel `i` (row-major within the tile).
    pub fn set(&mut self, i: usize, value: P) {
        let w = self.rows[0].len();
        self.rows[i / w][i % w] = value;
    }

    /// Sets every pixel from `src` (row-major within the tile), each as `from` makes it.
    pub fn copy_from<Q>(&mut self, src: &[Q], from: impl Fn(&Q) -> P) {
        let w = self.rows[0].len();
        for (row, src) in self.rows.iter_mut().zip(src.chunks_exact(w)) {
            row.iter_mut().zip(src).for_each(|(p, q)| *p = from(q));
        }
    }
}

/// Renders every tile of `window` on rayon's threads: `render(state, tile, rows)` with a
/// `state` made by `init` once per worker (the wavefront's path slots and queues) and the
/// tile's `rows` of `pixels` (the window's, row-major) to write, `progress(done, total)` after
/// each tile from any thread. Tiles write straight into the image: no tile holds pixels of its
/// own that would be copied, and no memory is faulted in twice (with tiles' own buffers and a
/// copy, the fixed cost of a 256x256 render was twice as large). What each tile returns comes
/// back in tile order, whatever order the tiles ran in.
pub fn render_tiles<S, P: Send, T: Send>(
    window: &PixelWindow,
    pixels: &mut [P],
    progress: &(dyn Fn(usize, usize) + Sync),
    init: impl Fn() -> S + Sync + Send,
    render: impl Fn(&mut S, &Tile, TileRows<'_, P>) -> T + Sync + Send,
) -> Vec<(Tile, T)> {
    assert_eq!(pixels.len(), window.len(), "a buffer of the window's pixels");
    let (tx, ty) = Tile::grid_of(window);
    let total = (tx * ty) as usize;
    let mut rows: Vec<TileRows<P>> =
        (0..total).map(|_| TileRows { rows: Vec::with_capacity(TILE as usize) }).collect();
    for (y, row) in pixels.chunks_mut(window.w as usize).enumerate() {
        for (x, part) in row.chunks_mut(TILE as usize).enumerate() {
            rows[y / TILE as usize * tx as usize + x].rows.push(part);
        }
    }
    let done = AtomicUsize::new(0);
    rows.into_par_iter()
        .enumerate()
        .map_init(init, |state, (t, rows)| {
            let tile = Tile::in_window(t as u32, window);
            let out = render(state, &tile, rows);
            progress(done.fetch_add(1, Ordering::Relaxed) + 1, total);
            (tile, out)
        })
        .collect()
}

/// [`render_tiles`] for a film that splats its samples `margin` pixels beyond their own
/// (`PixelFilter::splats`): the tiles cover the window grown by the margin within the image
/// `width` x `height` (pixels outside the window whose samples reach into it), each
/// `render(state, tile, rect)` returns its sums over `rect` (its pixels and its margin, within
/// the window), and they are added into `pixels` by `add` as the tiles finish. The sums are
/// exact, so the order they finish in does not change a bit.
#[expect(clippy::too_many_arguments, reason = "render_tiles' arguments, and the margin's three")]
pub fn splat_tiles<S, P: Send, Q, T: Send>(
    window: &PixelWindow,
    (width, height): (u32, u32),
    margin: u32,
    pixels: &mut [P],
    progress: &(dyn Fn(usize, usize) + Sync),
    init: impl Fn() -> S + Sync + Send,
    render: impl Fn(&mut S, &Tile, &PixelWindow) -> (Vec<Q>, T) + Sync + Send,
    add: impl Fn(&mut P, &Q) + Sync,
) -> Vec<(Tile, T)> {
    assert_eq!(pixels.len(), window.len(), "a buffer of the window's pixels");
    let samples = window.grown(margin, width, height);
    let (tx, ty) = Tile::grid_of(&samples);
    let total = (tx * ty) as usize;
    let film = std::sync::Mutex::new(pixels);
    let done = AtomicUsize::new(0);
    (0..total)
        .into_par_iter()
        .map_init(init, |state, t| {
            let tile = Tile::in_window(t as u32, &samples);
            let rect = tile.reach(margin, window);
            let (sums, out) = render(state, &tile, &rect);
            {
                // A tile that panicked while it held the lock left whole pixels behind.
                let mut film = film.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
                for (k, p) in sums.iter().enumerate() {
                    let (x, y) = (rect.x0 + k as u32 % rect.w, rect.y0 + k as u32 / rect.w);
                    add(&mut film[window.index(x, y)], p);
                }
            }
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
    fn render_tiles_gives_every_tile_its_own_pixels_in_order_and_reports_each() {
        let window = PixelWindow { x0: 5, y0: 3, w: 37, h: 21 };
        let reports = std::sync::Mutex::new(Vec::new());
        let mut pixels = vec![(u32::MAX, 0); window.len()];
        let tiles = render_tiles(
            &window,
            &mut pixels,
            &|done, total| reports.lock().unwrap().push((done, total)),
            || 0u32,
            |calls, tile, mut rows| {
                *calls += 1;
                (0..tile.len()).for_each(|i| rows.set(i as usize, tile.pixel(i)));
                tile.len()
            },
        );
        for (t, (tile, n)) in tiles.iter().enumerate() {
            assert_eq!((*tile, *n), (Tile::in_window(t as u32, &window), tile.len()));
        }
        // Each pixel was written by the tile that holds it, with its own coordinates.
        for (k, &(x, y)) in pixels.iter().enumerate() {
            assert_eq!(window.index(x, y), k);
        }
        let mut reports = reports.into_inner().unwrap();
        reports.sort();
        assert_eq!(reports, (1..=tiles.len()).map(|d| (d, tiles.len())).collect::<Vec<_>>());
    }

    #[test]
    fn splat_tiles_cover_the_window_and_its_margin_and_add_every_tiles_sums() {
        // Each tile adds 1 to every pixel it reaches; a pixel's count is the number of tiles
        // whose pixels lie within the margin of it (9 inside, fewer at the image's edges).
        let (width, height, margin) = (40, 37, 2);
        let window = PixelWindow { x0: 5, y0: 0, w: 30, h: 20 };
        let mut counts = vec![0u32; window.len()];
        let tiles = splat_tiles(
            &window,
            (width, height),
            margin,
            &mut counts,
            &|_, _| {},
            || (),
            |_, tile, rect| {
                assert_eq!(*rect, tile.reach(margin, &window));
                (vec![1u32; rect.len()], *tile)
            },
            |a, b| *a += b,
        );
        // The tiles cover the pixels within the margin of the window, each once.
        let samples = window.grown(margin, width, height);
        assert_eq!(samples, PixelWindow { x0: 3, y0: 0, w: 34, h: 22 });
        let mut covered = vec![0; samples.len()];
        for (t, _) in &tiles {
            (0..t.len()).map(|i| t.pixel(i)).for_each(|(x, y)| covered[samples.index(x, y)] += 1);
        }
        assert!(covered.iter().all(|&c| c == 1));
        // Each pixel counts the tiles with a pixel within the margin of it.
        let m = margin as i64;
        let near = |x: u32, y: u32| {
            let (x, y) = (x as i64, y as i64);
            let within = |a0: u32, n: u32, a: i64| a0 as i64 <= a + m && (a0 + n) as i64 > a - m;
            tiles.iter().filter(|(t, _)| within(t.x0, t.w, x) && within(t.y0, t.h, y)).count() as u32
        };
        for (k, &c) in counts.iter().enumerate() {
            let (x, y) = (window.x0 + k as u32 % window.w, window.y0 + k as u32 / window.w);
            assert_eq!(c, near(x, y), "pixel ({x}, {y})");
        }
    }

    #[test]
    fn tile_rows_copy_a_tiles_pixels_into_place() {
        let window = PixelWindow { x0: 0, y0: 0, w: 20, h: 3 };
        let mut pixels = vec![0u32; window.len()];
        render_tiles(
            &window,
            &mut pixels,
            &|_, _| {},
            || (),
            |_, tile, mut rows| {
                let own: Vec<u32> =
                    (0..tile.len()).map(|i| tile.pixel(i)).map(|(x, y)| 100 * y + x).collect();
                rows.copy_from(&own, |&v| v);
            },
        );
        assert!(pixels.iter().enumerate().all(|(k, &v)| v == 100 * (k as u32 / 20) + k as u32 % 20));
    }
}
