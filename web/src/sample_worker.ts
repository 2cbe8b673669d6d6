// The worker that fetches the parallel coordinates' samples (api.ts, fetchSample): the page's main
// thread gets the body as a transferred ArrayBuffer, without receiving 7 MB itself.
import { fetchSampleBody, type SampleReply } from './api';

const scope = self as unknown as { onmessage: ((e: MessageEvent<{ id: number; url: string }>) => void) | null; postMessage(m: SampleReply, transfer?: Transferable[]): void };

scope.onmessage = (e) => {
  const { id, url } = e.data;
  fetchSampleBody(url)
    .then((buffer) => scope.postMessage({ id, buffer }, [buffer]))
    .catch((err: unknown) => scope.postMessage({ id, error: err instanceof Error ? err.message : String(err) }));
};
