// A tiny static file server for the browser tests: the repository's web/ and runtime/src/gpu/
// (the kernels' WGSL), plus folders the test mounts (baked files it made), on 127.0.0.1 only.
import http from 'node:http';
import fs from 'node:fs/promises';
import path from 'node:path';

const TYPES = /** @type {Record<string, string>} */ ({
  '.html': 'text/html; charset=utf-8',
  '.js': 'text/javascript; charset=utf-8',
  '.json': 'application/json',
  '.wgsl': 'text/plain; charset=utf-8',
  '.glb': 'model/gltf-binary',
  '.gltf': 'model/gltf+json',
  '.bin': 'application/octet-stream',
  '.hce': 'application/octet-stream',
  '.wasm': 'application/wasm',
  '.png': 'image/png',
  '.css': 'text/css',
});

/**
 * Serves `mounts` (URL prefix → directory) on 127.0.0.1 at a free port.
 * @param {Record<string, string>} mounts e.g. { '/web/': '/repo/web' }
 * @returns {Promise<{ url: string, close: () => Promise<void> }>}
 */
export async function serve(mounts) {
  const server = http.createServer(async (req, res) => {
    try {
      const url = new URL(req.url ?? '/', 'http://127.0.0.1');
      const pathname = decodeURIComponent(url.pathname);
      for (const [prefix, dir] of Object.entries(mounts)) {
        if (!pathname.startsWith(prefix)) continue;
        const file = path.resolve(dir, pathname.slice(prefix.length));
        if (file !== path.resolve(dir) && !file.startsWith(path.resolve(dir) + path.sep)) break;
        const body = await fs.readFile(file);
        res.writeHead(200, {
          'content-type': TYPES[path.extname(file)] ?? 'application/octet-stream',
          'cache-control': 'no-store',
        });
        res.end(body);
        return;
      }
      res.writeHead(404).end('not found');
    } catch {
      res.writeHead(404).end('not found');
    }
  });
  await new Promise((resolve) => server.listen(0, '127.0.0.1', () => resolve(undefined)));
  const address = server.address();
  if (address === null || typeof address === 'string') throw new Error('no port');
  return {
    url: `http://127.0.0.1:${address.port}`,
    close: () => new Promise((resolve) => server.close(() => resolve(undefined))),
  };
}
