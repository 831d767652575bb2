// fracture: placeholder translation unit until the fracture module lands (keeps the library target non-empty).
namespace fdem::fracture {
int module_version() { return 0; }
}  // namespace fdem::fracture
