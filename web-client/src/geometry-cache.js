// The browser's geometry cache: the frames of this design's last compact
// join, kept in IndexedDB under the name the server gave them (the welcome's
// `geometry`, a SHA-256 of exactly those frames). A warm visit draws them at
// once, before the link is even open, and offers the name in its hello
// (`cached_geometry`): when the design has not changed since, the server
// skips the frames (the welcome says `geometry_cached`); when it has, or the
// name is stale, the server sends the frames as usual and they replace the
// cached drawing, and the snapshot drops any part the cache had that the
// design no longer has. Only the last few designs are kept.

const DB_NAME = 'vsculpt-geometry';
const STORE = 'joins';
/** How many designs' geometry is kept (the least recently saved goes first). */
export const KEEP_DESIGNS = 4;

/** The read index.html started while the code loaded ({ design, db, entry }), if any: taken once. */
let early = window.vsculptEarlyGeometry || null;

/** The cache's database, opened once per page (by index.html when it could); rejects where the browser has no IndexedDB (or refuses it). */
let opened = early ? early.db : null;
function database() {
  if (!opened) {
    opened = new Promise((resolve, reject) => {
      if (!window.indexedDB) throw new Error('no IndexedDB');
      const req = indexedDB.open(DB_NAME, 1);
      req.onupgradeneeded = () => req.result.createObjectStore(STORE);
      req.onsuccess = () => resolve(req.result);
      req.onerror = () => reject(req.error);
      req.onblocked = () => reject(new Error('geometry cache blocked'));
    });
  }
  return opened;
}

/** Resolves with the request's result when its transaction has completed. */
function done(tx, req) {
  return new Promise((resolve, reject) => {
    tx.oncomplete = () => resolve(req ? req.result : undefined);
    tx.onerror = tx.onabort = () => reject(tx.error);
  });
}

/** The server origin's geometry cache, one entry per design id: { hash, frames: [ArrayBuffer], saved }. */
export class GeometryCache {
  /** Design `design`'s last join geometry, or null (nothing kept, or no IndexedDB here). Never rejects. */
  async load(design) {
    try {
      const started = early && early.design === design ? early.entry : null;
      early = null;
      let entry;
      if (started) {
        entry = await started;
      } else {
        const db = await database();
        const tx = db.transaction(STORE, 'readonly');
        entry = await done(tx, tx.objectStore(STORE).get(design));
      }
      const valid = entry && typeof entry.hash === 'string' && Array.isArray(entry.frames) && entry.frames.every((f) => f instanceof ArrayBuffer);
      return valid ? entry : null;
    } catch (e) {
      return null;
    }
  }

  /** Keeps `frames` (ArrayBuffers, not used elsewhere afterwards) as design `design`'s geometry named `hash`; drops the oldest designs beyond KEEP_DESIGNS. Never rejects. */
  async save(design, hash, frames) {
    try {
      const db = await database();
      const tx = db.transaction(STORE, 'readwrite');
      const store = tx.objectStore(STORE);
      store.put({ hash, frames, saved: Date.now() }, design);
      const all = store.getAll();
      const keys = store.getAllKeys();
      // Requests of a transaction complete in order: `all` has its result when `keys` has.
      keys.onsuccess = () => {
        const byAge = keys.result.map((k, i) => [k, all.result[i].saved]).sort((a, b) => b[1] - a[1]);
        for (const [k] of byAge.slice(KEEP_DESIGNS)) store.delete(k);
      };
      await done(tx);
    } catch (e) {
      // A full or refused store only costs the next visit the frames.
    }
  }
}
