#!/usr/bin/env bash
# Writes the netCDF seeds of the reader's fuzz target (netcdf_reader/*.nc) with ncgen, an
# independent writer: small grids (2 x 2 x 4) in the three classic flavours and the layouts the
# reader accepts (descending lat, repeated lon seam, radius in m, a record dimension, fill
# values, packed shorts). Run it again only to change the seeds.
set -euo pipefail
out=$(cd "$(dirname "$0")" && pwd)/netcdf_reader
mkdir -p "$out"
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
values="1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15, 16"
contest_vars() {  # contest_vars TYPE DIMS [ATTRIBUTES, @ standing for the variable's name]
  for v in temperature vx vy vz 'thermal\ conductivity' 'thermal\ expansivity' 'temperature\ anomaly' \
           'spin\ transition-induced\ density\ anomaly'; do
    local extra=${3:-}
    echo "  $1 $v($2) ; $v:units = \"K\" ; ${extra//@/$v}"
  done
}
contest_data() {
  for v in temperature vx vy vz 'thermal\ conductivity' 'thermal\ expansivity' 'temperature\ anomaly' \
           'spin\ transition-induced\ density\ anomaly'; do
    echo "  $v = $1 ;"
  done
}
seed() {  # seed NAME KIND CDL
  printf '%s\n' "$3" > "$tmp/$1.cdl"
  ncgen -k "$2" -o "$out/$1.nc" "$tmp/$1.cdl"
}
for kind in nc3 nc6 nc5; do
  seed "plain-$kind" $kind "netcdf plain {
dimensions: lat = 2 ; r = 2 ; lon = 4 ;
variables:
  double lat(lat) ; lat:units = \"degrees_north\" ; double r(r) ; r:units = \"km\" ;
  double lon(lon) ; lon:units = \"degrees_east\" ;
$(contest_vars float 'lat, r, lon')
data:
  lat = 45, -45 ; r = 3485, 6371 ; lon = 0, 90, 180, 270 ;
$(contest_data "$values")
}"
done
seed layout nc6 "netcdf layout {
dimensions: longitude = 5 ; radius = 2 ; latitude = 2 ;
variables:
  float longitude(longitude) ; longitude:units = \"degrees_east\" ;
  float radius(radius) ; radius:units = \"m\" ; float latitude(latitude) ; latitude:units = \"degrees_north\" ;
$(contest_vars float 'radius, longitude, latitude')
data:
  longitude = -180, -90, 0, 90, 180 ; radius = 6371000, 3485000 ; latitude = 45, -45 ;
$(contest_data "1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15, 16, 17, 18, 19, 20")
}"
seed fill nc3 "netcdf fill {
dimensions: lat = 2 ; r = 2 ; lon = 4 ;
variables:
  double lat(lat) ; double r(r) ; r:units = \"km\" ; double lon(lon) ;
$(contest_vars float 'lat, r, lon' '@:_FillValue = -999.f ; @:missing_value = -998.f ;')
data:
  lat = -45, 45 ; r = 3485, 6371 ; lon = 0, 90, 180, 270 ;
$(contest_data "1, 2, -999, 4, 5, _, 7, 8, -998, 10, NaN, 12, 13, 14, 15, 16")
}"
seed packed nc3 "netcdf packed {
dimensions: lat = 2 ; r = 2 ; lon = 4 ;
variables:
  double lat(lat) ; double r(r) ; double lon(lon) ;
$(contest_vars short 'lat, r, lon' '@:scale_factor = 0.5 ; @:add_offset = 1000. ;')
  short T(lat, r, lon) ;
data:
  lat = -45, 45 ; r = 3485, 6371 ; lon = 0, 90, 180, 270 ;
$(contest_data "$values")
  T = $values ;
}"
seed record nc6 "netcdf record {
dimensions: r = UNLIMITED ; lat = 2 ; lon = 4 ;
variables:
  double lat(lat) ; double r(r) ; r:units = \"km\" ; double lon(lon) ;
$(contest_vars float 'r, lat, lon')
data:
  lat = -45, 45 ; r = 3485, 6371 ; lon = 0, 90, 180, 270 ;
$(contest_data "$values")
}"
ls -l "$out"
