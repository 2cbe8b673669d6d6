// Entry point of the browser UI: asks the server what it serves (GET /api/info), builds the App
// (app.ts) and, for the browser tests only, installs their hooks before the first state is sent.
import { fetchInfo } from './api';
import { App } from './app';
import { installTestHooks, testHooksWanted } from './test_hooks';

// Set by web/build.mjs: true only in the tests' build (web/dist-test); false, the hooks are not in the bundle.
declare const RAYPC_TEST_HOOKS: boolean;

fetchInfo()
  .then((info) => {
    const app = new App(info);
    if (RAYPC_TEST_HOOKS && testHooksWanted()) installTestHooks(app);
    app.start();
  })
  .catch((e) => {
    const status = document.getElementById('status');
    if (status) status.textContent = `cannot start: ${(e as Error).message}`;
  });
