// The build web/test/vite.test.js runs: relative asset URLs (the app is served from a
// subdirectory there), es2022 for the top-level await, and no warning for the one large chunk
// (three.js's WebGPU build is most of it).
export default { base: './', build: { target: 'es2022', chunkSizeWarningLimit: 2048 } };
