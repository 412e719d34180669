#!/usr/bin/env bash
# Bad scene files fail with a message naming the file and the key, a non-zero exit, and no
# output file. Needs HYPERSHAPE_BIN (set by CTest).
. "$(dirname "$0")/lib.sh"

good() {
  cat <<'YAML'
geometry: {base: circle}
mesh: {h: 0.1, degree: 1}
effects:
  neo_hookean: {E: 500, nu: 0.49}
  dirichlet_patch: {center: [1.0, 0.0], radius: 0.5}
  gaussian_traction: {center: [-1.0, 0.0], direction: [0.0, 1.0], gamma: 0.2}
load: {target: 0.3}
YAML
}

# expect NAME SED-EXPRESSION EXPECTED-KEY-TEXT
expect() {
  local name=$1 expr=$2 key=$3 scene="$work/$1.yaml" out="$work/$1.h5"
  good | sed -e "$expr" > "$scene"
  local msg code
  msg=$("$bin" solve "$scene" -o "$out" 2>&1 >/dev/null); code=$?
  if [ "$code" -eq 0 ]; then echo "FAIL $name: exit 0"; fails=$((fails+1)); return; fi
  if ! grep -qF "$scene" <<<"$msg"; then echo "FAIL $name: message does not name the file: $msg"; fails=$((fails+1)); return; fi
  if ! grep -qF "$key" <<<"$msg"; then echo "FAIL $name: message does not name '$key': $msg"; fails=$((fails+1)); return; fi
  if ls "$work/$1".h5* "$work/$1".xdmf* >/dev/null 2>&1; then echo "FAIL $name: output left behind"; fails=$((fails+1)); return; fi
  echo "ok   $name: $msg"; passes=$((passes+1))
}

expect missing_load      '/^load:/d'                               'load'
expect missing_material  '/neo_hookean/d'                          'effects'
expect wrong_type_h      's/h: 0.1/h: fine/'                       'mesh.h'
expect wrong_type_center 's/center: \[1.0, 0.0\]/center: 1.0/'     'effects.dirichlet_patch.center'
expect nu_too_large      's/nu: 0.49/nu: 0.5/'                     'effects.neo_hookean.nu'
expect negative_E        's/E: 500/E: -1/'                         'effects.neo_hookean.E'
expect radius_zero       's/radius: 0.5/radius: 0/'                'effects.dirichlet_patch.radius'
expect radius_negative   's/radius: 0.5/radius: -0.2/'             'effects.dirichlet_patch.radius'
expect unknown_effect    's/gaussian_traction/gausian_traction/'   'effects.gausian_traction'
expect unknown_key       's/gamma: 0.2/gamma: 0.2, sigma: 1/'      'effects.gaussian_traction.sigma'
expect unknown_section   's/^load:/loads:/'                        'loads'
expect unknown_mesh_file 's/{base: circle}/{base: file, file: nowhere.msh}/' 'geometry.file'
expect unknown_base      's/base: circle/base: torus/'             'geometry.base'
expect bad_degree        's/degree: 1/degree: 3/'                  'mesh.degree'
expect alpha_and_target  's/{target: 0.3}/{target: 0.3, alpha: 2}/' 'load'
expect spring_no_stiffness 's/^load:/  spring: {box: [-1, -1, 1, 1]}\nload:/' 'effects.spring.stiffness'
expect spring_negative   's/^load:/  spring: {normal_stiffness: -2}\nload:/' 'effects.spring.normal_stiffness'
expect spring_both_forms 's/^load:/  spring: {stiffness: 1, tangential_stiffness: 1}\nload:/' 'effects.spring.stiffness'
expect inclusions_no_ratio 's/nu: 0.49}/nu: 0.49, inclusions: 2, inclusion_radius: 0.2}/' 'effects.neo_hookean.inclusion_ratio'
expect inclusions_fraction 's/nu: 0.49}/nu: 0.49, inclusions: 1.5, inclusion_radius: 0.2, inclusion_ratio: 3}/' 'effects.neo_hookean.inclusions'
expect step_growth_below_1 's/^load: {target: 0.3}/load: {target: 0.3}\nsolver: {step_growth: 0.5}/' 'solver.step_growth'
expect rim_and_refinement 's/h: 0.1, degree: 1/h: 0.1, degree: 1, rim: 0.01, clamp_refinement: 0.25/' 'mesh.rim'
expect rim_on_polygon    's/{base: circle}/{polygon: [[0, 0], [1, 0], [0, 1]]}/; s/degree: 1/degree: 1, rim: 0.01/' 'mesh.rim'
expect not_yaml          's/^geometry: {base: circle}/geometry: {base: [circle/' 'YAML'

# The datasets' 2D mesh.rim sets the mesh size at the patch ends (instead of h x clamp_refinement):
# finer than the default quarter of h, the mesh has more vertices.
verts() { good | sed -e "$1" > "$work/v.yaml"; "$bin" solve "$work/v.yaml" -o "$work/v.h5" 2>/dev/null | grep -o '[0-9]* vertices' | cut -d' ' -f1; }
n_default=$(verts 's/x/x/') n_rim=$(verts 's/degree: 1/degree: 1, rim: 0.004/')
if [ -n "$n_default" ] && [ -n "$n_rim" ] && [ "$n_rim" -gt "$n_default" ]; then
  echo "ok   2D rim 0.004: $n_rim vertices against $n_default (clamp_refinement 0.25)"; passes=$((passes+1))
else echo "FAIL 2D rim: '$n_rim' vertices against '$n_default'"; fails=$((fails+1)); fi

# An unwritable output directory: rejected before any work.
good > "$work/ok.yaml"
if "$bin" solve "$work/ok.yaml" -o "$work/no/such/dir/out.h5" 2>/dev/null; then
  echo "FAIL unwritable output accepted"; fails=$((fails+1)); else echo "ok   unwritable output"; passes=$((passes+1)); fi

# PETSc's -help opens with the project's own settings (YAML keys, the solver's with defaults).
help=$("$bin" solve -help 2>&1 | head -6)
grep -q "solver:  rtol 1e-09, max_newton 12" <<<"$help" && grep -q "path_rtol 0.3" <<<"$help" && grep -q "step_growth 0 (0: by dimension)" <<<"$help" &&
  ok "-help lists the solver's keys with their defaults" || fail "-help: $help"
finish
