import { defineConfig } from "vite";

// The gateway serves dist/ at /; `npm run dev` proxies the API to a gateway on :8080.
export default defineConfig({
  base: "/",
  build: { outDir: "dist", emptyOutDir: true, chunkSizeWarningLimit: 1024 },
  server: { proxy: { "/v1": "http://127.0.0.1:8080" } },
});
