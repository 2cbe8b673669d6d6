// d3-geo-projection ships no type declarations: the projections the map panel uses, typed as
// d3-geo's (the package builds them with d3-geo's geoProjection).
declare module 'd3-geo-projection' {
  import type { GeoProjection } from 'd3-geo';
  export function geoMollweide(): GeoProjection;
  export function geoHammer(): GeoProjection;
  export function geoRobinson(): GeoProjection;
}
