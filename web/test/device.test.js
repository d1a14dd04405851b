// requestDevice (src/device.js) against a stubbed navigator.gpu (no browser needed): Chromium
// answers requestAdapter with null for a moment while its GPU process restarts, so the runtime
// asks again a few times before saying there is no adapter, and says so when there is none.
import test from 'node:test';
import assert from 'node:assert/strict';
import { requestDevice } from '../src/device.js';

/**
 * A navigator.gpu whose requestAdapter answers null `nulls` times, then an adapter.
 * @param {number} nulls
 */
function stub(nulls) {
  const calls = { adapter: 0 };
  const device = { label: 'stub device' };
  const adapter = {
    limits: { maxStorageBufferBindingSize: 1 << 27, maxBufferSize: 1 << 28 },
    /** @param {any} descriptor */
    async requestDevice(descriptor) {
      assert.equal(descriptor.requiredLimits.maxBufferSize, 1 << 28);
      return device;
    },
  };
  const gpu = {
    async requestAdapter() {
      calls.adapter += 1;
      return calls.adapter > nulls ? adapter : null;
    },
  };
  Object.defineProperty(globalThis, 'navigator', { value: { gpu }, configurable: true, writable: true });
  return { calls, adapter, device };
}

test('an adapter that answers null at first is asked again', async () => {
  const { calls, adapter, device } = stub(2);
  const got = await requestDevice();
  assert.equal(got.adapter, adapter);
  assert.equal(got.device, device);
  assert.equal(calls.adapter, 3);
});

test('no adapter after the retries is a clear error, not a hang', async () => {
  const { calls } = stub(Infinity);
  const started = Date.now();
  await assert.rejects(requestDevice(), /WebGPU gives no adapter on this machine/);
  assert.equal(calls.adapter, 4);
  assert.ok(Date.now() - started < 5000, 'gave up within seconds');
});
