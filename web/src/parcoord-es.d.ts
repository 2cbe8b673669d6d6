// parcoord-es ships no type declarations; the UI uses its chainable API through this loose type.
declare module 'parcoord-es' {
  // eslint-disable-next-line @typescript-eslint/no-explicit-any
  const ParCoords: (config?: Record<string, unknown>) => (selector: string | HTMLElement) => any;
  export default ParCoords;
}
