// The one error type of the runtime: what is wrong, where (a location as `hce validate` writes
// it, e.g. `objects[2].triangles[517]`) and the SPEC.md section it enforces, so that a damaged
// file gets a message a user can act on and never reaches the GPU.

export class HceError extends Error {
  /**
   * @param {string} location where, e.g. `file[4132]` or `objects[0].mesh`
   * @param {string} message what is wrong, naming the SPEC.md section where there is one
   */
  constructor(location, message) {
    super(location ? `${location}: ${message}` : message);
    this.name = 'HceError';
    this.location = location;
    this.reason = message;
  }
}
