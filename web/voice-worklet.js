// The microphone's samples at 16 kHz, 20 ms at a time: the audio thread's blocks gathered
// into 16-bit chunks of 320 samples and posted to the page. A context running at another
// rate (browsers that cannot open the microphone at 16 kHz) is brought down to 16 kHz here,
// each output sample the mean of the input samples it spans.
const RATE = 16000;
const CHUNK = 320;

class Chunker extends AudioWorkletProcessor {
  constructor() {
    super();
    this.chunk = new Int16Array(CHUNK);
    this.filled = 0;
    /** Input samples per output sample (`sampleRate` is the context's). */
    this.step = sampleRate / RATE;
    this.sum = 0;
    this.count = 0;
    this.due = this.step;
  }

  push(/** @type {number} */ value) {
    const s = Math.max(-1, Math.min(1, value));
    this.chunk[this.filled++] = s < 0 ? s * 32768 : s * 32767;
    if (this.filled === CHUNK) {
      this.port.postMessage(this.chunk.buffer, [this.chunk.buffer]);
      this.chunk = new Int16Array(CHUNK);
      this.filled = 0;
    }
  }

  process(inputs) {
    const channel = inputs[0] && inputs[0][0];
    if (!channel) return true;
    for (let i = 0; i < channel.length; i++) {
      if (this.step === 1) { this.push(channel[i]); continue; }
      this.sum += channel[i];
      this.count++;
      if (this.count >= this.due) {
        this.push(this.sum / this.count);
        this.sum = 0;
        this.due += this.step - this.count;
        this.count = 0;
      }
    }
    return true;
  }
}

registerProcessor('faceanim-chunker', Chunker);
